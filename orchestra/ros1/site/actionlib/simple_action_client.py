"""actionlib.SimpleActionClient: send one goal at a time and follow it to its result.

The goal's state comes from the server's ``status`` list, ``feedback`` and ``result``
topics (messages about other goals are ignored). ``get_state()`` reports actionlib's
simple view: RECALLING reads as PENDING and PREEMPTING as ACTIVE until the result says how
the goal ended. Timeouts are ``rospy.Duration``s or seconds; zero means wait forever.
"""
from __future__ import annotations

import threading
import time
from collections.abc import Callable
from typing import Any

from orchestra.node import runtime
from orchestra.node.rostime import Time
from orchestra.node.topics import Publisher, Subscriber
from orchestra.tf.convert import to_sec

from . import goals
from .goals import ACTIVE, LOST, PENDING, PREEMPTING, RECALLING, TERMINAL, ActionTypes

__all__ = ["SimpleActionClient", "SimpleGoalState"]


class SimpleGoalState:
    PENDING, ACTIVE, DONE = 0, 1, 2

    @staticmethod
    def to_string(n: int) -> str:
        return {0: "PENDING", 1: "ACTIVE", 2: "DONE"}.get(n, f"UNKNOWN({n})")


class SimpleActionClient:
    def __init__(self, ns: str, ActionSpec: type):  # noqa: N803 - actionlib's name
        self.types = ActionTypes.of(ActionSpec)
        self._ns = goals.action_namespace(ns)
        self._cond = threading.Condition()
        self._goal_id: Any = None
        self._status = LOST
        self._text = ""
        self._result: Any = None
        self._simple_state = SimpleGoalState.DONE
        self._callbacks: tuple = (None, None, None)
        self._server_seen = False
        self._goal_pub = Publisher(self._ns + "/goal", self.types.action_goal, queue_size=10)
        self._cancel_pub = Publisher(self._ns + "/cancel", goals.goal_id_class(), queue_size=10)
        self._subs = [
            Subscriber(self._ns + "/status", goals.status_array_class(), self._on_status,
                       queue_size=1),
            Subscriber(self._ns + "/feedback", self.types.action_feedback, self._on_feedback,
                       queue_size=0),
            Subscriber(self._ns + "/result", self.types.action_result, self._on_result,
                       queue_size=0),
        ]

    # --- the server ------------------------------------------------------------------------------

    def _server_ready(self) -> bool:
        """A server's status arrived, it takes our goals and cancels, and its feedback and
        result reach us (else the first feedback of a goal sent now could be lost)."""
        return (self._server_seen and self._goal_pub.get_num_connections() > 0
                and self._cancel_pub.get_num_connections() > 0
                and all(sub.get_num_connections() > 0 for sub in self._subs))

    def wait_for_server(self, timeout: Any = None) -> bool:
        """True once a server is connected both ways (``_server_ready``); False if
        ``timeout`` passes first (zero/None: wait for ever)."""
        return self._wait(self._server_ready, timeout, poll=True)

    def _wait(self, ready: Callable[[], bool], timeout: Any, poll: bool = False) -> bool:
        seconds = to_sec(timeout) if timeout is not None else 0.0
        deadline = time.monotonic() + seconds if seconds > 0 else None
        with self._cond:
            while not ready():
                if runtime.is_shutdown():
                    return False
                remaining = 0.1 if deadline is None else min(0.1, deadline - time.monotonic())
                if remaining <= 0:
                    return False
                self._cond.wait(remaining)
        return True

    # --- goals -----------------------------------------------------------------------------------

    def send_goal(self, goal: Any, done_cb: Callable | None = None,
                  active_cb: Callable | None = None,
                  feedback_cb: Callable | None = None) -> None:
        """Send ``goal`` (any goal being followed is forgotten, not cancelled)."""
        msg = self.types.action_goal()
        msg.goal_id = goals.new_goal_id()
        msg.header.stamp = msg.goal_id.stamp
        msg.goal = goal
        with self._cond:
            self._goal_id = msg.goal_id
            self._status, self._text, self._result = PENDING, "", None
            self._simple_state = SimpleGoalState.PENDING
            self._callbacks = (done_cb, active_cb, feedback_cb)
        self._goal_pub.publish(msg)

    def send_goal_and_wait(self, goal: Any, execute_timeout: Any = None,
                           preempt_timeout: Any = None) -> int:
        """Send, wait up to ``execute_timeout``; on timeout cancel and wait up to
        ``preempt_timeout`` for the server to confirm. Returns ``get_state()``."""
        self.send_goal(goal)
        if not self.wait_for_result(execute_timeout):
            runtime.logdebug("Canceling goal")
            self.cancel_goal()
            self.wait_for_result(preempt_timeout)
        return self.get_state()

    def wait_for_result(self, timeout: Any = None) -> bool:
        """True once the goal is done; False on timeout (zero/None: wait for ever)."""
        if self._goal_id is None:
            runtime.logerr("Called wait_for_result when no goal exists")
            return False
        return self._wait(lambda: self._simple_state == SimpleGoalState.DONE, timeout)

    def get_result(self) -> Any:
        if self._goal_id is None:
            runtime.logerr("Called get_result when no goal is running")
            return None
        return self._result

    def get_state(self) -> int:
        """actionlib_msgs/GoalStatus value of the goal (LOST when none is followed)."""
        if self._goal_id is None:
            return LOST
        status = self._status
        if status == RECALLING:
            return PENDING
        if status == PREEMPTING:
            return ACTIVE
        return status

    def get_goal_status_text(self) -> str:
        if self._goal_id is None:
            runtime.logerr("Called get_goal_status_text when no goal is running")
            return "ERROR: Called get_goal_status_text when no goal is running"
        return self._text

    def cancel_goal(self) -> None:
        if self._goal_id is not None:
            self._cancel_pub.publish(goals.goal_id_class()(stamp=Time(), id=self._goal_id.id))

    def cancel_all_goals(self) -> None:
        self._cancel_pub.publish(goals.goal_id_class()(stamp=Time(), id=""))

    def cancel_goals_at_and_before_time(self, time: Time) -> None:
        self._cancel_pub.publish(goals.goal_id_class()(stamp=time, id=""))

    def stop_tracking_goal(self) -> None:
        with self._cond:
            self._goal_id = None

    # --- from the server -------------------------------------------------------------------------

    def _ours(self, status: Any) -> bool:
        return self._goal_id is not None and status.goal_id.id == self._goal_id.id

    def _on_status(self, msg: Any) -> None:
        calls = []
        with self._cond:
            self._server_seen = True
            for status in msg.status_list:
                if self._ours(status) and self._simple_state != SimpleGoalState.DONE:
                    calls = self._update(status.status, status.text)
            self._cond.notify_all()
        _run(calls)

    def _on_feedback(self, msg: Any) -> None:
        with self._cond:
            if not self._ours(msg.status):
                return
            calls = self._update(msg.status.status, msg.status.text)
            feedback_cb = self._callbacks[2]
        _run(calls)
        if feedback_cb is not None:
            feedback_cb(msg.feedback)

    def _on_result(self, msg: Any) -> None:
        with self._cond:
            if not self._ours(msg.status) or self._simple_state == SimpleGoalState.DONE:
                return
            calls = self._update(msg.status.status, msg.status.text, result=msg.result,
                                 final=True)
            self._cond.notify_all()
        _run(calls)

    def _update(self, status: int, text: str, result: Any = None,
                final: bool = False) -> list[tuple[Callable, tuple]]:
        """Record what the server said about our goal; the user's callbacks to run (outside
        the lock) for the simple-state transitions it causes."""
        done_cb, active_cb, _ = self._callbacks
        calls: list[tuple[Callable, tuple]] = []
        if status in TERMINAL and not final:
            status = self._status if self._status not in TERMINAL else status
            # a terminal status only counts with its result (which carries the result message)
        self._status, self._text = status, text
        if self._simple_state == SimpleGoalState.PENDING and status in (ACTIVE, PREEMPTING) \
                or (final and self._simple_state == SimpleGoalState.PENDING
                    and status not in (goals.REJECTED, goals.RECALLED)):
            self._simple_state = SimpleGoalState.ACTIVE
            if active_cb is not None:
                calls.append((active_cb, ()))
        if final:
            self._result = result
            self._simple_state = SimpleGoalState.DONE
            if done_cb is not None:
                calls.append((done_cb, (self.get_state(), result)))
        return calls


def _run(calls: list[tuple[Callable, tuple]]) -> None:
    for fn, args in calls:
        fn(*args)

