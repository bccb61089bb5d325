"""What both ends of an action share: the message classes of an action type, goal ids, and
actionlib's status values and their meaning.

The protocol is actionlib's, five topics under the action's namespace: ``goal``
(``<Name>ActionGoal``) and ``cancel`` (actionlib_msgs/GoalID) from clients to the server;
``status`` (actionlib_msgs/GoalStatusArray, latched, a few times a second), ``feedback`` and
``result`` (``<Name>ActionFeedback``/``<Name>ActionResult``) from the server, every one
carrying the goal's id and status.
"""
from __future__ import annotations

import itertools
import threading
from dataclasses import dataclass
from typing import Any

from orchestra.node import runtime
from orchestra.node.msg import get_message_class
from orchestra.node.rostime import Time

PENDING, ACTIVE, PREEMPTED, SUCCEEDED, ABORTED, REJECTED = 0, 1, 2, 3, 4, 5
PREEMPTING, RECALLING, RECALLED, LOST = 6, 7, 8, 9
TERMINAL = frozenset({PREEMPTED, SUCCEEDED, ABORTED, REJECTED, RECALLED, LOST})


def status_class() -> Any:
    """actionlib_msgs/GoalStatus (message classes are built on first use)."""
    return get_message_class("actionlib_msgs/GoalStatus")


def status_array_class() -> Any:
    return get_message_class("actionlib_msgs/GoalStatusArray")


def goal_id_class() -> Any:
    return get_message_class("actionlib_msgs/GoalID")


@dataclass(frozen=True)
class ActionTypes:
    """The six classes behind an ``<Name>Action`` class (what genaction generates)."""

    action_goal: type
    action_result: type
    action_feedback: type
    goal: type
    result: type
    feedback: type

    @classmethod
    def of(cls, action_spec: type) -> ActionTypes:
        spec = action_spec()
        return cls(type(spec.action_goal), type(spec.action_result), type(spec.action_feedback),
                   type(spec.action_goal.goal), type(spec.action_result.result),
                   type(spec.action_feedback.feedback))


def action_namespace(ns: str) -> str:
    """The action's topic namespace: ``ns`` resolved and remapped, as actionlib does."""
    resolved = runtime.resolve_name(ns)
    return runtime.get_runtime().remaps.get(resolved, resolved)


_counter = itertools.count(1)
_counter_lock = threading.Lock()


def new_goal_id(stamp: Time | None = None) -> Any:
    """A GoalID unique to this node: ``<caller id>-<n>-<seconds>``, actionlib's form."""
    stamp = Time.now() if stamp is None else stamp
    with _counter_lock:
        n = next(_counter)
    return goal_id_class()(stamp=stamp, id=f"{runtime.get_caller_id()}-{n}-{stamp.to_sec():.3f}")
