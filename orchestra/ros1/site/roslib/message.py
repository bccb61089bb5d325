"""roslib.message: message and service classes by type name (None when unknown, as roslib)."""
from __future__ import annotations

from typing import Any

from orchestra.node.exceptions import ROSException
from orchestra.node.msg import Message
from orchestra.node.msg import get_message_class as _message_class
from orchestra.node.msg import get_service_class as _service_class

__all__ = ["Message", "get_message_class", "get_service_class"]


def get_message_class(message_type: str, reload_on_error: bool = False) -> Any:
    try:
        return _message_class(message_type)
    except (ROSException, ValueError):
        return None


def get_service_class(service_type: str, reload_on_error: bool = False) -> Any:
    try:
        return _service_class(service_type)
    except (ROSException, ValueError):
        return None
