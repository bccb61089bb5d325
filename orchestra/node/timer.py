"""``Timer``: call a function periodically from its own thread (rospy.Timer's contract)."""
from __future__ import annotations

import logging
import threading
from dataclasses import dataclass
from typing import Callable

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
    """``callback(TimerEvent)`` every ``period`` (a Duration or seconds) until ``shutdown()``
    or node shutdown; ``oneshot`` runs it once. Ticks are scheduled from the start time, so
    a slow callback does not make the timer drift; missed ticks are skipped."""

    def __init__(self, period: Duration | float, callback: Callable[[TimerEvent], None],
                 oneshot: bool = False, reset: bool = False):
        super().__init__(daemon=True, name="timer")
        self._period = period.to_sec() if isinstance(period, Duration) else float(period)
        if self._period <= 0:
            raise ValueError("Timer period must be positive")
        self._callback = callback
        self._oneshot = oneshot
        self._cancelled = threading.Event()
        self.start()

    def shutdown(self) -> None:
        self._cancelled.set()

    def run(self) -> None:
        from orchestra.node.runtime import is_shutdown

        period = Duration.from_sec(self._period)
        expected = Time.now() + period
        last_expected = last_real = None
        last_duration = None
        while not self._cancelled.is_set() and not is_shutdown():
            delay = (expected - Time.now()).to_sec()
            if delay > 0 and self._cancelled.wait(delay):
                return
            if is_shutdown():
                return
            real = Time.now()
            event = TimerEvent(last_expected, last_real, expected, real, last_duration)
            try:
                self._callback(event)
            except Exception:  # a failing callback must not kill the timer thread silently
                log.exception("error in timer callback")
            last_duration = (Time.now() - real).to_sec()
            if self._oneshot:
                return
            last_expected, last_real = expected, real
            expected = expected + period
            now = Time.now()
            while expected < now:
                expected = expected + period
