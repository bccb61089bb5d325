"""orchestra's node API: write ROS 1 nodes in Python without ROS installed.

Names and behaviour follow rospy (``init_node``, ``Publisher``, ``Subscriber``, ``Service``,
``ServiceProxy``, params, ``Time``/``Duration``/``Rate``, ``loginfo``...), and the wire
protocol is ROS 1's TCPROS, so these nodes talk to rospy/roscpp nodes and to a real
rosmaster as well as to orchestra's. Message classes come from ``orchestra.node.msg``.
"""
from orchestra.node.exceptions import (
                                       ROSException,
                                       ROSInitException,
                                       ROSInterruptException,
                                       ROSTimeMovedBackwardsException,
                                       SerializationError,
                                       ServiceException,
                                       TransportException,
)
from orchestra.node.msg import AnyMsg, get_message_class, get_service_class
from orchestra.node.rostime import Duration, Rate, Time, get_rostime, get_time, sleep
from orchestra.node.runtime import (
                                       DEBUG,
                                       ERROR,
                                       FATAL,
                                       INFO,
                                       WARN,
                                       delete_param,
                                       get_caller_id,
                                       get_master_uri,
                                       get_name,
                                       get_namespace,
                                       get_node_uri,
                                       get_param,
                                       get_param_cached,
                                       get_param_names,
                                       get_published_topics,
                                       has_param,
                                       init_node,
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
                                       myargv,
                                       on_shutdown,
                                       remap_name,
                                       resolve_name,
                                       search_param,
                                       set_param,
                                       signal_shutdown,
                                       spin,
                                       wait_for_message,
)
from orchestra.node.services import Service, ServiceProxy, wait_for_service
from orchestra.node.timer import Timer, TimerEvent
from orchestra.node.topics import Publisher, Subscriber

__all__ = [
    "AnyMsg", "DEBUG", "Duration", "ERROR", "FATAL", "INFO", "WARN", "Publisher", "ROSException",
    "ROSInitException",
    "ROSInterruptException", "ROSTimeMovedBackwardsException", "Rate", "SerializationError",
    "Service", "ServiceException",
    "ServiceProxy", "Subscriber", "Time", "Timer", "TimerEvent", "TransportException", "delete_param",
    "get_caller_id", "get_master_uri", "get_message_class", "get_name", "get_namespace",
    "get_node_uri", "get_param", "get_param_cached", "get_param_names",
    "get_published_topics", "get_rostime", "get_service_class", "get_time", "has_param",
    "init_node", "is_shutdown", "logdebug", "logdebug_once", "logdebug_throttle",
    "logdebug_throttle_identical", "logerr", "logerr_once", "logerr_throttle",
    "logerr_throttle_identical", "logfatal", "logfatal_once", "logfatal_throttle",
    "logfatal_throttle_identical", "loginfo", "loginfo_once", "loginfo_throttle",
    "loginfo_throttle_identical", "logwarn", "logwarn_once", "logwarn_throttle",
    "logwarn_throttle_identical", "myargv", "on_shutdown", "remap_name",
    "resolve_name", "search_param", "set_param", "signal_shutdown", "sleep", "spin",
    "wait_for_message", "wait_for_service",
]
