"""rospy.client: init_node, spin, params and waits of orchestra's runtime."""
from __future__ import annotations

import os
import threading

from orchestra.node import runtime as _runtime
from orchestra.node.runtime import (
    DEBUG,
    ERROR,
    FATAL,
    INFO,
    WARN,
    delete_param,
    get_param,
    get_param_cached,
    get_param_names,
    get_published_topics,
    get_runtime,
    has_param,
    is_initialized,
    myargv,
    on_shutdown,
    search_param,
    set_param,
    spin,
    wait_for_message,
)
from orchestra.rpc import master_uri_from_env

from . import topics as _topics
from .msproxy import MasterProxy

__all__ = ["DEBUG", "ERROR", "FATAL", "INFO", "WARN", "delete_param", "get_master",
           "get_param", "get_param_cached", "get_param_names", "get_published_topics",
           "has_param", "init_node", "myargv", "on_shutdown", "search_param", "set_param",
           "spin", "wait_for_message"]

_master = None
_master_lock = threading.Lock()


def get_master(env: os._Environ | dict = os.environ):
    """The master as a ``MasterProxy`` (this node's master, else ``ROS_MASTER_URI``);
    usable before ``init_node``, as in rospy."""
    global _master
    with _master_lock:
        if _master is None:
            uri = (get_runtime().master_uri if is_initialized()
                   else master_uri_from_env(env))
            _master = MasterProxy(uri)
    return _master


def init_node(name: str, argv: list[str] | None = None, anonymous: bool = False,
              log_level: int | None = None, disable_rostime: bool = False,
              disable_rosout: bool = False, disable_signals: bool = False,
              xmlrpc_port: int = 0, tcpros_port: int = 0) -> None:
    """orchestra's ``init_node``, then the topics the script created before it."""
    _runtime.init_node(name, argv, anonymous, log_level, disable_rostime, disable_rosout,
                       disable_signals, xmlrpc_port, tcpros_port)
    _topics.start_deferred()
