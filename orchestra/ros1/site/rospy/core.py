"""rospy.core: life cycle, logging and small helpers, from orchestra's runtime."""
from __future__ import annotations

import os

from orchestra.node.exceptions import ROSException
from orchestra.node.runtime import (
    get_node_uri,
    is_initialized,
    is_shutdown,
    logdebug,
    logdebug_once,
    logdebug_throttle,
    logdebug_throttle_identical,
    logerr,
    logerr_once,
    logerr_throttle,
    logerr_throttle_identical,
    logfatal,
    logfatal_once,
    logfatal_throttle,
    logfatal_throttle_identical,
    loginfo,
    loginfo_once,
    loginfo_throttle,
    loginfo_throttle_identical,
    logwarn,
    logwarn_once,
    logwarn_throttle,
    logwarn_throttle_identical,
    signal_shutdown,
)
from orchestra.node.tcpros import parse_rosrpc_uri

#: rospy's deprecated name for loginfo
logout = loginfo

__all__ = [
    "get_node_uri", "get_ros_root", "is_initialized", "is_shutdown", "is_shutdown_requested",
    "logdebug", "logdebug_once", "logdebug_throttle", "logdebug_throttle_identical", "logerr",
    "logerr_once", "logerr_throttle", "logerr_throttle_identical", "logfatal", "logfatal_once",
    "logfatal_throttle", "logfatal_throttle_identical", "loginfo", "loginfo_once",
    "loginfo_throttle", "loginfo_throttle_identical", "logout", "logwarn", "logwarn_once",
    "logwarn_throttle", "logwarn_throttle_identical", "parse_rosrpc_uri", "signal_shutdown",
]


def is_shutdown_requested() -> bool:
    """rospy distinguishes "requested" from "done"; orchestra's shutdown is one flag."""
    return is_shutdown()


def get_ros_root(required: bool = False, env: dict | None = None) -> str | None:
    """``ROS_ROOT`` from ``env`` (default the process environment); no ROS install needs
    one, so it is usually None — ``required`` makes that a ROSException, as in rospy."""
    root = (os.environ if env is None else env).get("ROS_ROOT")
    if required and not root:
        raise ROSException("ROS_ROOT is not set")
    return root
