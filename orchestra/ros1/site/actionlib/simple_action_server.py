"""actionlib.SimpleActionServer: one goal at a time, a newer goal preempting the current one.

Semantics are actionlib's: a goal newer than the current and the pending one replaces the
pending one (which is cancelled: "canceled because another goal was received") and asks
the current one to stop (``is_preempt_requested()``, the preempt callback). With an
``execute_cb`` a thread runs it for each accepted goal; a callback that returns without a
terminal state aborts its goal. A cancel message names one goal, every goal stamped up to a
time, or all goals (empty id, zero stamp).
"""
from __future__ import annotations

import logging
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from orchestra.node import runtime
from orchestra.node.exceptions import ROSException
from orchestra.node.rostime import Time
from orchestra.node.topics import Publisher, Subscriber

from . import goals
from .goals import (
    ABORTED,
    ACTIVE,
    PENDING,
    PREEMPTED,
    PREEMPTING,
    RECALLED,
    RECALLING,
    SUCCEEDED,
    TERMINAL,
    ActionTypes,
)

__all__ = ["SimpleActionServer"]

log = logging.getLogger(__name__)

#: actionlib's defaults (params ``actionlib_status_frequency``, ``<ns>/status_list_timeout``)
STATUS_FREQUENCY = 5.0
STATUS_LIST_TIMEOUT = 5.0


@dataclass
class _Goal:
    goal_id: Any
    goal: Any
    status: int = PENDING
    text: str = ""
    finished_at: float | None = field(default=None)

    @property
    def stamp(self) -> Time:
        return self.goal_id.stamp


class SimpleActionServer:
    def __init__(self, name: str, ActionSpec: type, execute_cb: Callable | None = None,  # noqa: N803
                 auto_start: bool = True):
        self.types = ActionTypes.of(ActionSpec)
        self.execute_callback = execute_cb
        self.goal_callback: Callable | None = None
        self.preempt_callback: Callable | None = None
        self._cond = threading.Condition(threading.RLock())
        self._goals: dict[str, _Goal] = {}
        self._current: _Goal | None = None
        self._next: _Goal | None = None
        self._new_goal = False
        self._preempt_request = False
        self._new_goal_preempt_request = False
        self._last_cancel = Time()
        self._started = False
        self._ns = goals.action_namespace(name)
        self._status_pub = Publisher(self._ns + "/status", goals.status_array_class(),
                                     queue_size=50, latch=True)
        self._result_pub = Publisher(self._ns + "/result", self.types.action_result,
                                     queue_size=50)
        self._feedback_pub = Publisher(self._ns + "/feedback", self.types.action_feedback,
                                       queue_size=50)
        self._goal_sub: Subscriber | None = None
        self._cancel_sub: Subscriber | None = None
        frequency = _status_frequency()
        self._status_period = 1.0 / frequency if frequency > 0 else 0.0
        self._list_timeout = float(runtime.get_param(self._ns + "/status_list_timeout",
                                                     STATUS_LIST_TIMEOUT))
        self._executor: threading.Thread | None = None
        if execute_cb is not None:
            self._executor = threading.Thread(target=self._execute_loop, daemon=True,
                                              name=f"action-{self._ns}")
        if auto_start:
            self.start()

    # --- life cycle ------------------------------------------------------------------------------

    def start(self) -> None:
        """Start taking goals (actionlib: call it after registering the callbacks)."""
        with self._cond:
            if self._started:
                return
            self._started = True
        self._goal_sub = Subscriber(self._ns + "/goal", self.types.action_goal, self._on_goal,
                                    queue_size=0)
        self._cancel_sub = Subscriber(self._ns + "/cancel", goals.goal_id_class(), self._on_cancel,
                                      queue_size=0)
        if self._status_period > 0:
            threading.Thread(target=self._status_loop, daemon=True,
                             name=f"action-status-{self._ns}").start()
        if self._executor is not None:
            self._executor.start()
        self._publish_status()

    def register_goal_callback(self, cb: Callable[[], None]) -> None:
        if self.execute_callback is not None:
            log.warning("SimpleActionServer %s: the goal callback is not used with an "
                        "execute callback", self._ns)
        else:
            self.goal_callback = cb

    def register_preempt_callback(self, cb: Callable[[], None]) -> None:
        self.preempt_callback = cb

    # --- the user's side ----------------------------------------------------------------------------

    def accept_new_goal(self) -> Any:
        """Make the pending goal the current one (ACTIVE) and return its goal message; a
        current goal still active is preempted first."""
        with self._cond:
            if not self._new_goal or self._next is None:
                log.error("SimpleActionServer %s: accept_new_goal() with no new goal", self._ns)
                return None
            if self.is_active() and self._current is not None:
                self._finish(self._current, PREEMPTED, None,
                             "This goal was canceled because another goal was received by the "
                             "simple action server")
            self._current, self._next = self._next, None
            self._new_goal = False
            self._preempt_request = self._new_goal_preempt_request
            self._new_goal_preempt_request = False
            self._set_status(self._current, ACTIVE if self._current.status == PENDING
                             else PREEMPTING, "")
            return self._current.goal

    def is_new_goal_available(self) -> bool:
        return self._new_goal

    def is_preempt_requested(self) -> bool:
        return self._preempt_request

    def is_active(self) -> bool:
        current = self._current
        return current is not None and current.status in (ACTIVE, PREEMPTING)

    def set_succeeded(self, result: Any = None, text: str = "") -> None:
        self._finish_current(SUCCEEDED, result, text)

    def set_aborted(self, result: Any = None, text: str = "") -> None:
        self._finish_current(ABORTED, result, text)

    def set_preempted(self, result: Any = None, text: str = "") -> None:
        self._finish_current(PREEMPTED, result, text)

    def get_default_result(self) -> Any:
        return self.types.result()

    def publish_feedback(self, feedback: Any) -> None:
        current = self._current
        if current is None:
            return
        msg = self.types.action_feedback()
        msg.header.stamp = Time.now()
        msg.status = self._status_msg(current)
        msg.feedback = feedback
        self._feedback_pub.publish(msg)

    # --- goals and their states ----------------------------------------------------------------

    def _status_msg(self, g: _Goal) -> Any:
        return goals.status_class()(goal_id=g.goal_id, status=g.status, text=g.text)

    def _set_status(self, g: _Goal, status: int, text: str) -> None:
        g.status, g.text = status, text
        self._publish_status()

    def _finish_current(self, status: int, result: Any, text: str) -> None:
        with self._cond:
            if self._current is None or not self.is_active():
                log.error("SimpleActionServer %s: no active goal to set to %d", self._ns, status)
                return
            self._finish(self._current, status, result, text)

    def _finish(self, g: _Goal, status: int, result: Any, text: str) -> None:
        g.status, g.text, g.finished_at = status, text, time.monotonic()
        msg = self.types.action_result()
        msg.header.stamp = Time.now()
        msg.status = self._status_msg(g)
        msg.result = self.get_default_result() if result is None else result
        self._result_pub.publish(msg)
        self._publish_status()

    def _on_goal(self, msg: Any) -> None:
        goal_id = msg.goal_id
        if goal_id.stamp.is_zero():
            goal_id.stamp = Time.now()
        with self._cond:
            if goal_id.id in self._goals:  # a repeat of a goal we already track
                return
            g = _Goal(goal_id, msg.goal)
            self._goals[goal_id.id] = g
            if not self._last_cancel.is_zero() and goal_id.stamp <= self._last_cancel:
                self._finish(g, RECALLED, None,
                             "This goal handle was canceled by the action server because its "
                             "timestamp is before the timestamp of the last cancel request")
                return
            newer_than_current = self._current is None or g.stamp >= self._current.stamp
            newer_than_next = self._next is None or g.stamp >= self._next.stamp
            if not (newer_than_current and newer_than_next):
                self._finish(g, RECALLED if g.status == PENDING else PREEMPTED, None,
                             "This goal was canceled because another goal was received by the "
                             "simple action server")
                return
            if self._next is not None and self._next is not self._current:
                self._finish(self._next, RECALLED if self._next.status in (PENDING, RECALLING)
                             else PREEMPTED, None,
                             "This goal was canceled because another goal was received by the "
                             "simple action server")
            self._next = g
            self._new_goal = True
            self._new_goal_preempt_request = False
            if self.is_active():
                self._preempt_request = True
                if self.preempt_callback is not None:
                    self.preempt_callback()
            if self.goal_callback is not None:
                self.goal_callback()
            self._publish_status()
            self._cond.notify_all()

    def _on_cancel(self, msg: Any) -> None:
        cancel_all = msg.id == "" and msg.stamp.is_zero()
        with self._cond:
            if not msg.stamp.is_zero() and msg.stamp > self._last_cancel:
                self._last_cancel = msg.stamp
            for g in list(self._goals.values()):
                if g.status in TERMINAL:
                    continue
                if not (cancel_all or g.goal_id.id == msg.id
                        or (not msg.stamp.is_zero() and g.stamp <= msg.stamp)):
                    continue
                if g is self._current and self.is_active():
                    self._set_status(g, PREEMPTING, g.text)
                    self._preempt_request = True
                    if self.preempt_callback is not None:
                        self.preempt_callback()
                elif g is self._next:
                    # a pending goal cancelled before it ran is recalled at once (actionlib
                    # recalls it when the user next looks; nobody can have seen it yet)
                    self._next = None
                    self._new_goal = False
                    self._finish(g, RECALLED, None, "")

    # --- threads -------------------------------------------------------------------------------

    def _execute_loop(self) -> None:
        while not runtime.is_shutdown():
            with self._cond:
                while not self._new_goal and not runtime.is_shutdown():
                    self._cond.wait(0.1)
                if runtime.is_shutdown():
                    return
                goal = self.accept_new_goal()
            if goal is None or self.execute_callback is None:
                continue
            try:
                self.execute_callback(goal)
                if self.is_active():
                    runtime.logwarn("Your executeCallback did not set the goal to a terminal "
                                    "status. This is a bug in your ActionServer "
                                    "implementation. Fix your code! For now, the ActionServer "
                                    "will set this goal to aborted")
                    self.set_aborted(None, "No terminal state was set.")
            except Exception as exc:  # the user's callback: report, abort, keep serving
                runtime.logerr("Exception in your execute callback: %s", exc)
                if self.is_active():
                    self.set_aborted(None, f"Exception in execute callback: {exc}")

    def _status_loop(self) -> None:
        while not runtime.is_shutdown():
            time.sleep(self._status_period)
            self._publish_status()

    def _publish_status(self) -> None:
        now = time.monotonic()
        with self._cond:
            for key, g in list(self._goals.items()):
                if g.finished_at is not None and now - g.finished_at > self._list_timeout:
                    del self._goals[key]
            statuses = [self._status_msg(g) for g in self._goals.values()]
        msg = goals.status_array_class()(status_list=statuses)
        msg.header.stamp = Time.now()
        try:
            self._status_pub.publish(msg)
        except ROSException as exc:  # shutting down: the publisher may be gone
            log.debug("status of %s not published: %s", self._ns, exc)


def _status_frequency() -> float:
    """``actionlib_status_frequency`` found by searchParam from the node, else 5 Hz."""
    key = runtime.search_param("actionlib_status_frequency")
    return float(runtime.get_param(key, STATUS_FREQUENCY)) if key else STATUS_FREQUENCY

