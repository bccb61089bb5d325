"""rospy for orchestra's ROS 1 layer: unmodified ``import rospy`` code on orchestra's node runtime.

Every public name of rospy is here, with rospy's signatures; each one is orchestra.node's
object (or a thin adapter where rospy's signature differs), so behaviour is the runtime's.

The names resolve on first use (PEP 562 ``__getattr__``): a node pays for the runtime when
it calls ``init_node``/``Publisher``..., not when it imports rospy (rospy itself imports its
whole stack eagerly; see bench/bench_rospy_layer.py for the difference). ``from rospy import
*`` and ``dir(rospy)`` see everything.
"""
from __future__ import annotations

import importlib
from typing import Any

#: public name -> the submodule of this package that defines it
_WHERE = {
    # client
    "init_node": "client", "spin": "client", "myargv": "client", "get_master": "client",
    "get_published_topics": "client", "wait_for_message": "client", "on_shutdown": "client",
    "get_param": "client", "get_param_cached": "client", "get_param_names": "client",
    "set_param": "client", "delete_param": "client", "has_param": "client",
    "search_param": "client", "DEBUG": "client", "INFO": "client", "WARN": "client",
    "ERROR": "client", "FATAL": "client",
    # timer, time
    "sleep": "timer", "Rate": "timer", "Timer": "timer", "TimerEvent": "timer",
    "Time": "rostime", "Duration": "rostime", "get_rostime": "rostime", "get_time": "rostime",
    # core
    "is_shutdown": "core", "signal_shutdown": "core", "get_node_uri": "core",
    "get_ros_root": "core", "parse_rosrpc_uri": "core", "logout": "core",
    # names
    "get_name": "names", "get_caller_id": "names", "get_namespace": "names",
    "resolve_name": "names", "remap_name": "names",
    # topics, services, messages
    "Publisher": "topics", "Subscriber": "topics", "Message": "topics",
    "SubscribeListener": "topics", "AnyMsg": "msg", "Header": "msg",
    "Service": "service", "ServiceProxy": "service", "wait_for_service": "service",
    "ServiceException": "service", "MasterProxy": "msproxy",
    # exceptions
    "ROSException": "exceptions", "ROSSerializationException": "exceptions",
    "ROSInitException": "exceptions", "ROSInterruptException": "exceptions",
    "ROSInternalException": "exceptions", "ROSTimeMovedBackwardsException": "exceptions",
    "TransportException": "exceptions", "TransportTerminated": "exceptions",
    "TransportInitError": "exceptions",
}
for _level in ("debug", "info", "warn", "err", "fatal"):
    for _form in ("", "_throttle", "_throttle_identical", "_once"):
        _WHERE[f"log{_level}{_form}"] = "core"

__all__ = sorted(_WHERE)


#: rospy's submodules that code reaches as attributes after a bare ``import rospy``
_SUBMODULES = frozenset({"client", "core", "exceptions", "msg", "msproxy", "names", "rostime",
                         "service", "timer", "topics"})


def __getattr__(name: str) -> Any:
    if name in _SUBMODULES:
        return importlib.import_module(f"{__name__}.{name}")
    module = _WHERE.get(name)
    if module is None:
        raise AttributeError(f"module 'rospy' has no attribute {name!r}")
    value = getattr(importlib.import_module(f"{__name__}.{module}"), name)
    globals()[name] = value  # resolved once; later lookups are plain module attributes
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_WHERE) | _SUBMODULES)
