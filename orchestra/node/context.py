"""The node of this process: the one ``NodeRuntime`` that ``init_node`` created, or none.

rospy's API is module-level functions (``rospy.Publisher(...)`` needs no node object), so
publishers, subscribers, services and the logger services must find the process's node
somewhere. They find it here, not in ``runtime``: the runtime imports them to build a node,
so their importing the runtime back would make an import cycle. This module imports nothing
of the node package at run time; it only holds the reference.
"""
from __future__ import annotations

import threading
from typing import TYPE_CHECKING

from orchestra.node.exceptions import ROSInitException

if TYPE_CHECKING:
    from orchestra.node.runtime import NodeRuntime

_current: NodeRuntime | None = None
lock = threading.Lock()
"""Held while a node is being made current (``init_node`` runs once per process)."""


def current() -> NodeRuntime:
    """The process's node; ROSInitException when ``init_node`` has not been called."""
    node = _current
    if node is None:
        raise ROSInitException("init_node() has not been called in this process")
    return node


def current_or_none() -> NodeRuntime | None:
    return _current


def set_current(node: NodeRuntime | None) -> None:
    """Make ``node`` the process's node (None: there is none any more)."""
    global _current
    _current = node
