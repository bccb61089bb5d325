"""The per-node logger services every ROS 1 node offers: ``~get_loggers``, ``~set_logger_level``.

They are what ``rosconsole list|get|set``, rqt_logger_level and ``rosservice call
/node/set_logger_level`` talk to. As in rospy, the loggers are the process's Python
``logging`` loggers (every name in the logging registry, the root logger excepted): the
node's own messages (``loginfo`` ...) go through the logger ``rosout``, orchestra's library
through ``orchestra.node.*``. Setting a level calls ``setLevel`` on that logger at once.

Level names are roscpp's, which the ROS tools expect (rosconsole compares lower-case names):
``get_loggers`` answers ``debug``/``info``/``warn``/``error``/``fatal``, and an unknown level
in ``set_logger_level`` is a service error. rospy itself answers upper-case names and
accepts a bad level silently (it only logs an error); see docs/node.md.
"""
from __future__ import annotations

import logging

#: ROS level names, lowest first, with their Python logging levels
LEVELS = (("debug", logging.DEBUG), ("info", logging.INFO), ("warn", logging.WARNING),
          ("error", logging.ERROR), ("fatal", logging.CRITICAL))
LEVEL_NAMES = tuple(name for name, _ in LEVELS)
_BY_NAME = dict(LEVELS)


def level_name(level: int) -> str:
    """The ROS name of a Python logging level (levels in between round down, as filtering
    does: 25 only lets INFO's neighbours above it through, so it reads ``info``)."""
    name = "debug"
    for candidate, value in LEVELS:
        if level >= value:
            name = candidate
    return name


def python_level(name: str) -> int:
    """The Python level of a ROS level name (any case); ValueError for an unknown name."""
    try:
        return _BY_NAME[name.strip().lower()]
    except KeyError:
        raise ValueError(f"unknown logger level [{name}] (levels: "
                         f"{', '.join(LEVEL_NAMES)})") from None


def logger_levels() -> list[tuple[str, str]]:
    """(name, effective level) of every logger of this process, sorted by name."""
    names = sorted(list(logging.Logger.manager.loggerDict))  # list(): one atomic copy
    return [(name, level_name(logging.getLogger(name).getEffectiveLevel())) for name in names]


def set_logger_level(logger: str, level: str) -> None:
    """Set ``logger``'s level to the ROS level ``level`` (ValueError if unknown)."""
    value = python_level(level)
    logging.getLogger(logger).setLevel(value)


def offer_services() -> list:
    """Register ``~get_loggers`` and ``~set_logger_level`` for this process's node."""
    from orchestra.node.msg import get_message_class, get_service_class
    from orchestra.node.services import Service

    get_loggers = get_service_class("roscpp/GetLoggers")
    set_level = get_service_class("roscpp/SetLoggerLevel")
    logger_class = get_message_class("roscpp/Logger")

    def handle_get(request):
        return get_loggers._response_class(loggers=[logger_class(name=name, level=level)
                                                    for name, level in logger_levels()])

    def handle_set(request):
        set_logger_level(request.logger, request.level)
        return set_level._response_class()

    return [Service("~get_loggers", get_loggers, handle_get),
            Service("~set_logger_level", set_level, handle_set)]
