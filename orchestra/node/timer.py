"""``Timer``: call a function periodically from its own thread (rospy.Timer's contract)."""
from __future__ import annotations

import logging
import threading
import time as _time
from collections.abc import Callable
from dataclasses import dataclass

from orchestra.node import rostime
from orchestra.node.exceptions import ROSInterruptException, ROSTimeMovedBackwardsException
from orchestra.node.rostime import Duration, Time

log = logging.getLogger(__name__)


@dataclass
class TimerEvent:
    """What a timer callback is told: when it was due and when it actually ran."""

    last_expected: Time | None
    last_real: Time | None
    current_expected: Time
    current_real: Time
    last_duration: float | None


class Timer(threading.Thread):
    """``callback(TimerEvent)`` every ``period`` (a Duration or seconds) of ROS time until
    ``shutdown()`` or node shutdown; ``oneshot`` runs it once. Ticks are scheduled from the
    start time, so a slow callback does not make the timer drift; a late tick runs once and
    the ticks missed before it ran are skipped.

    Under simulated time the schedule starts at the first /clock and follows it. When /clock
    jumps backwards the timer stops (rospy's timer thread dies of the exception), or with
    ``reset=True`` restarts its schedule from the new time."""

    def __init__(self, period: Duration | float, callback: Callable[[TimerEvent], None],
                 oneshot: bool = False, reset: bool = False):
        super().__init__(daemon=True, name="timer")
        self._period = period.to_sec() if isinstance(period, Duration) else float(period)
        if self._period <= 0:
            raise ValueError("Timer period must be positive")
        self._callback = callback
        self._oneshot = oneshot
        self._reset = reset
        self._cancelled = threading.Event()
        self.start()

    def shutdown(self) -> None:
        self._cancelled.set()
        rostime._wake_sleepers()

    def _wait_until(self, target: int, since: int) -> bool:
        """Wait until ROS time ``target`` (ns); False when cancelled. Under simulated time
        raises like ``rostime._wait_sim`` (``since``: the clock must not go below it)."""
        if rostime.is_wallclock():
            delay = (target - rostime._now_ns()) / 1e9
            return not (delay > 0 and self._cancelled.wait(delay))
        return rostime._wait_sim(target, since, self._cancelled) is not None

    def run(self) -> None:
        from orchestra.node.runtime import is_shutdown

        period = max(1, Duration.from_sec(self._period).to_nsec())
        try:
            now = rostime._first_clock(self._cancelled)
        except ROSInterruptException:
            return
        if now is None:
            return
        expected, since = now + period, now
        last_expected = last_real = None
        last_duration = None
        while not self._cancelled.is_set() and not is_shutdown():
            try:
                if not self._wait_until(expected, since):
                    return
            except ROSTimeMovedBackwardsException as exc:
                if not self._reset:
                    log.error("timer stopped: ROS time moved backwards by %.3f s "
                              "(Timer(..., reset=True) restarts instead)", exc.time)
                    return
                since = rostime._now_ns()
                expected = since + period
                continue
            except ROSInterruptException:
                return
            if is_shutdown():
                return
            real = Time.now()
            event = TimerEvent(last_expected, last_real, Time(0, expected), real, last_duration)
            started = _time.monotonic()
            try:
                self._callback(event)
            except Exception:  # a failing callback must not kill the timer thread silently
                log.exception("error in timer callback")
            last_duration = _time.monotonic() - started
            if self._oneshot:
                return
            last_expected, last_real = event.current_expected, real
            expected, since = expected + period, real.to_nsec()
            if expected < since:  # this tick ran late: skip the ones already missed
                expected += -(-(since - expected) // period) * period
