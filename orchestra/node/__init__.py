"""orchestra's node API: write ROS 1 nodes in Python without ROS installed.

Names and behaviour follow rospy (``init_node``, ``Publisher``, ``Subscriber``, ``Service``,
``ServiceProxy``, params, ``Time``/``Duration``/``Rate``, ``loginfo``...), and the wire
protocol is ROS 1's TCPROS, so these nodes talk to rospy/roscpp nodes and to a real
rosmaster as well as to orchestra's. Message classes come from ``orchestra.node.msg``.

The names load on first use (PEP 562 ``__getattr__``): importing ``orchestra.node.msg``
(every message import of the ROS 1 layer) must not pay for the runtime's XML-RPC and
networking stack; ``from orchestra.node import *`` and ``dir()`` still see every name.
"""
from __future__ import annotations

import importlib
from typing import Any

#: submodule -> the public names it defines (the one list of this package's API)
_EXPORTS: dict[str, tuple[str, ...]] = {
    "exceptions": ("ROSException", "ROSInitException", "ROSInterruptException",
        "ROSTimeMovedBackwardsException", "SerializationError", "ServiceException",
        "TransportException"),
    "msg": ("AnyMsg", "get_message_class", "get_service_class"),
    "rostime": ("Duration", "Rate", "Time", "get_rostime", "get_time", "sleep"),
    "runtime": ("DEBUG", "ERROR", "FATAL", "INFO", "WARN", "delete_param", "get_caller_id",
        "get_master_uri", "get_name", "get_namespace", "get_node_uri", "get_param",
        "get_param_cached", "get_param_names", "get_published_topics", "has_param", "init_node",
        "is_shutdown", "logdebug", "logdebug_once", "logdebug_throttle",
        "logdebug_throttle_identical", "logerr", "logerr_once", "logerr_throttle",
        "logerr_throttle_identical", "logfatal", "logfatal_once", "logfatal_throttle",
        "logfatal_throttle_identical", "loginfo", "loginfo_once", "loginfo_throttle",
        "loginfo_throttle_identical", "logwarn", "logwarn_once", "logwarn_throttle",
        "logwarn_throttle_identical", "myargv", "on_shutdown", "remap_name", "resolve_name",
        "search_param", "set_param", "signal_shutdown", "spin", "wait_for_message"),
    "services": ("Service", "ServiceProxy", "wait_for_service"),
    "timer": ("Timer", "TimerEvent"),
    "topics": ("Publisher", "Subscriber"),
}
_WHERE = {name: module for module, names in _EXPORTS.items() for name in names}
__all__ = sorted(_WHERE)


def __getattr__(name: str) -> Any:
    module = _WHERE.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(importlib.import_module(f"{__name__}.{module}"), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_WHERE))
