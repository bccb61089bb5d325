"""rospy.service / rospy.impl.tcpros_service: services of orchestra's runtime, rospy's
signatures (``Service(..., error_handler=...)``)."""
from __future__ import annotations

import sys
from collections.abc import Callable
from typing import Any

from orchestra.node import services as _services
from orchestra.node.exceptions import ServiceException
from orchestra.node.services import ServiceProxy, wait_for_service

__all__ = ["Service", "ServiceException", "ServiceProxy", "wait_for_service"]


class Service(_services.Service):
    """rospy.Service(name, service_class, handler, buff_size=65536, error_handler=None).

    ``error_handler(exception, exc_type, exc_value, traceback)`` is called when the handler
    raises (before the caller gets the error), as rospy does."""

    def __init__(self, name: str, service_class: Any, handler: Callable,
                 buff_size: int = 65536, error_handler: Callable | None = None):
        if error_handler is not None:
            handler = _reporting(handler, error_handler)
        super().__init__(name, service_class, handler)


def _reporting(handler: Callable, error_handler: Callable) -> Callable:
    def call(request: Any) -> Any:
        try:
            return handler(request)
        except Exception as exc:
            error_handler(exc, *sys.exc_info())
            raise
    return call
