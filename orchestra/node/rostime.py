"""ROS time values: ``Time`` (a point) and ``Duration`` (a span), secs + nsecs like ROS 1.

Both are normalised so that ``0 <= nsecs < 1e9``; on the wire they are two 32-bit integers
(unsigned for Time, signed for Duration), which is why they are kept as integers here rather
than floats: a round trip through a message must give back exactly what was sent.

ROS time is wall time, or simulated time when ``/use_sim_time`` is true at ``init_node``:
then ``Time.now()`` is the last ``/clock`` message and ``sleep``, ``Rate`` and ``Timer`` wait
for /clock to advance (see "the time source" below).
"""
from __future__ import annotations

import functools
import threading
import time as _time

from orchestra.node.exceptions import ROSInterruptException, ROSTimeMovedBackwardsException


def _normalise(secs: int, nsecs: int) -> tuple[int, int]:
    carry, nsecs = divmod(int(nsecs), 1_000_000_000)
    return int(secs) + carry, nsecs


@functools.total_ordering
class _TimeBase:
    __slots__ = ("secs", "nsecs")

    def __init__(self, secs: int | float = 0, nsecs: int = 0):
        if isinstance(secs, float):
            whole = int(secs // 1)
            nsecs = int(nsecs) + int(round((secs - whole) * 1e9))
            secs = whole
        self.secs, self.nsecs = _normalise(secs, nsecs)

    @classmethod
    def from_sec(cls, float_secs: float):
        return cls(float(float_secs))

    #: genpy's older name
    from_seconds = from_sec

    def set(self, secs: int, nsecs: int) -> None:
        """Both fields at once (genpy's ``set``), normalised."""
        self.secs, self.nsecs = _normalise(secs, nsecs)

    def canon(self):
        """genpy's normalisation; values here are always normal, so this is ``self``."""
        return self

    @classmethod
    def from_nsec(cls, nanoseconds: int):
        return cls(0, int(nanoseconds))

    def to_sec(self) -> float:
        return self.secs + self.nsecs / 1e9

    def to_nsec(self) -> int:
        return self.secs * 1_000_000_000 + self.nsecs

    #: genpy's other name for to_sec
    def to_time(self) -> float:
        return self.to_sec()

    def is_zero(self) -> bool:
        return self.secs == 0 and self.nsecs == 0

    def __bool__(self) -> bool:
        return not self.is_zero()

    def __eq__(self, other) -> bool:
        if not isinstance(other, _TimeBase):
            return NotImplemented
        return type(self) is type(other) and self.to_nsec() == other.to_nsec()

    def __lt__(self, other) -> bool:
        if not isinstance(other, type(self)):
            return NotImplemented
        return self.to_nsec() < other.to_nsec()

    def __hash__(self) -> int:
        return hash((type(self).__name__, self.to_nsec()))

    def __repr__(self) -> str:
        return f"{type(self).__name__}[{self.to_nsec()}]"

    def __str__(self) -> str:
        return str(self.to_nsec())


class Duration(_TimeBase):
    """A signed span of time."""

    __slots__ = ()

    def __neg__(self) -> Duration:
        return Duration(0, -self.to_nsec())

    def __abs__(self) -> Duration:
        return Duration(0, abs(self.to_nsec()))

    def __add__(self, other):
        if isinstance(other, Time):
            return Time(0, self.to_nsec() + other.to_nsec())
        if isinstance(other, Duration):
            return Duration(0, self.to_nsec() + other.to_nsec())
        return NotImplemented

    __radd__ = __add__

    def __sub__(self, other):
        if isinstance(other, Duration):
            return Duration(0, self.to_nsec() - other.to_nsec())
        return NotImplemented

    def __mul__(self, factor: float) -> Duration:
        return Duration(0, int(round(self.to_nsec() * factor)))

    __rmul__ = __mul__

    def __truediv__(self, divisor):
        if isinstance(divisor, Duration):
            return self.to_nsec() / divisor.to_nsec()
        return Duration(0, int(round(self.to_nsec() / divisor)))


class Time(_TimeBase):
    """A point in ROS time: wall time since the Unix epoch, or the simulated ``/clock``."""

    __slots__ = ()

    def __init__(self, secs: int | float = 0, nsecs: int = 0):
        super().__init__(secs, nsecs)
        if self.secs < 0:
            raise ValueError("Time cannot be negative")

    @classmethod
    def now(cls) -> Time:
        """The current ROS time: the last ``/clock`` message under simulated time (0 until
        the first one arrives), otherwise wall time."""
        return cls(0, _now_ns())

    def __add__(self, other):
        if isinstance(other, Duration):
            return Time(0, self.to_nsec() + other.to_nsec())
        return NotImplemented

    __radd__ = __add__

    def __sub__(self, other):
        if isinstance(other, Time):
            return Duration(0, self.to_nsec() - other.to_nsec())
        if isinstance(other, Duration):
            return Time(0, self.to_nsec() - other.to_nsec())
        return NotImplemented


# --- the time source ----------------------------------------------------------------------------
#
# Wall time unless init_node found /use_sim_time set: then ``_sim_ns`` holds the last /clock
# value (0 before the first message) and every sleep waits on ``_clock`` for it to advance.
# /clock messages, shutdown and Timer.shutdown() notify ``_clock``; waits also look again
# every half second, so nothing depends on a notification arriving.

_sim_ns: int | None = None
_clock = threading.Condition()
_shutdown_event = threading.Event()
_POLL = 0.5


def _now_ns() -> int:
    sim = _sim_ns
    return _time.time_ns() if sim is None else sim


def is_wallclock() -> bool:
    """True unless this node follows simulated time (``/use_sim_time`` at init_node)."""
    return _sim_ns is None


def _use_sim_time() -> None:
    """Switch to simulated time (init_node, when /use_sim_time is true): time is 0 until
    the first /clock message."""
    global _sim_ns
    with _clock:
        if _sim_ns is None:
            _sim_ns = 0


def _set_sim_time(stamp: Time) -> None:
    """A /clock message arrived (called from the /clock subscriber's thread)."""
    global _sim_ns
    with _clock:
        _sim_ns = stamp.to_nsec()
        _clock.notify_all()


def _wake_sleepers() -> None:
    """Make waits on the simulated clock look at shutdown/cancellation now. Not for signal
    handlers (it takes a lock): the runtime calls it from its cleanup thread."""
    with _clock:
        _clock.notify_all()


def get_time() -> float:
    """Current ROS time in float seconds (rospy.get_time)."""
    return _now_ns() / 1e9


def get_rostime() -> Time:
    return Time.now()


def _set_shutdown_event(event: threading.Event) -> None:
    """The node runtime hands over its shutdown event so sleeps wake up at shutdown."""
    global _shutdown_event
    _shutdown_event = event


def _to_ns(duration: float | Duration) -> int:
    if isinstance(duration, Duration):
        return duration.to_nsec()
    return int(round(float(duration) * 1e9))


def _wait_sim(target_ns: int | None, start_ns: int,
              cancelled: threading.Event | None = None) -> int | None:
    """Wait for the simulated clock: until it reaches ``target_ns``, or with ``target_ns``
    None until it is non-zero (the first /clock). Returns the clock value, None if
    ``cancelled`` got set. ROSInterruptException at shutdown;
    ROSTimeMovedBackwardsException when the clock goes below ``start_ns``."""
    with _clock:
        while True:
            if _shutdown_event.is_set():
                raise ROSInterruptException("ROS shutdown request")
            if cancelled is not None and cancelled.is_set():
                return None
            now = _sim_ns
            if now is None:  # cannot happen (no way back to wall time); do not hang
                return _now_ns()
            if now < start_ns:
                raise ROSTimeMovedBackwardsException((start_ns - now) / 1e9)
            reached = now > 0 if target_ns is None else now >= target_ns
            if reached:
                return now
            _clock.wait(_POLL)


def _first_clock(cancelled: threading.Event | None = None) -> int | None:
    """The current ROS time in ns; under simulated time, wait for the first /clock first."""
    if _sim_ns is None:
        return _time.time_ns()
    return _wait_sim(None, 0, cancelled)


def sleep(duration: float | Duration) -> None:
    """Sleep for ``duration`` of ROS time, waking up and raising ``ROSInterruptException``
    when the node shuts down. Under simulated time the sleep ends when /clock reaches the
    target (it waits for the first /clock before it starts counting) and raises
    ``ROSTimeMovedBackwardsException`` when /clock jumps back before the start."""
    span = _to_ns(duration)
    if _sim_ns is not None:
        start = _first_clock()
        assert start is not None  # None only when a cancel event is given
        _wait_sim(start + span, start)
        return
    if span <= 0:
        return
    if _shutdown_event.wait(span / 1e9):
        raise ROSInterruptException("ROS shutdown request")


class Rate:
    """Keep a loop at ``hz`` iterations per second of ROS time, absorbing the loop body's own
    time. Under wall time it runs on the monotonic clock; under simulated time on /clock.

    ``Rate.sleep`` raises ``ROSTimeMovedBackwardsException`` when /clock jumps back during the
    sleep, unless ``reset`` is true: then it returns and restarts the schedule from the new
    time. A jump back between two sleeps just restarts the schedule (as in rospy)."""

    def __init__(self, hz: float, reset: bool = False):
        if hz <= 0:
            raise ValueError("Rate needs a positive frequency")
        self.period = 1.0 / hz
        self._period_ns = int(round(1e9 / hz))
        self.reset = reset
        self._sim, self._last = self._clock_now()

    @staticmethod
    def _clock_now() -> tuple[bool, int]:
        if _sim_ns is None:
            return False, _time.monotonic_ns()
        return True, _sim_ns

    def _now(self) -> int:
        sim, now = self._clock_now()
        if sim != self._sim:  # made before init_node switched to simulated time
            self._sim, self._last = sim, now
        if now < self._last:  # the clock went back since the last sleep
            self._last = now
        return now

    def remaining(self) -> Duration:
        now = self._now()
        return Duration(0, self._last + self._period_ns - now)

    def sleep(self) -> None:
        now = self._now()
        deadline = self._last + self._period_ns
        if now > deadline + self._period_ns:
            # fell far behind (or the clock jumped ahead): restart the schedule, no burst
            deadline = now
        if not self._sim:
            self._last = deadline
            sleep(Duration(0, deadline - now))
            return
        try:
            _wait_sim(deadline, now)
        except ROSTimeMovedBackwardsException:
            if not self.reset:
                raise
            self._last = self._clock_now()[1]
            return
        self._last = deadline
