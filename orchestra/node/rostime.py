"""ROS time values: ``Time`` (a point) and ``Duration`` (a span), secs + nsecs like ROS 1.

Both are normalised so that ``0 <= nsecs < 1e9``; on the wire they are two 32-bit integers
(unsigned for Time, signed for Duration), which is why they are kept as integers here rather
than floats: a round trip through a message must give back exactly what was sent.
"""
from __future__ import annotations

import functools
import threading
import time as _time


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
    def from_sec(cls, seconds: float):
        return cls(float(seconds))

    @classmethod
    def from_nsec(cls, nanoseconds: int):
        return cls(0, int(nanoseconds))

    def to_sec(self) -> float:
        return self.secs + self.nsecs / 1e9

    def to_nsec(self) -> int:
        return self.secs * 1_000_000_000 + self.nsecs

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

    def __neg__(self) -> "Duration":
        return Duration(0, -self.to_nsec())

    def __abs__(self) -> "Duration":
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

    def __mul__(self, factor: float) -> "Duration":
        return Duration(0, int(round(self.to_nsec() * factor)))

    __rmul__ = __mul__

    def __truediv__(self, divisor):
        if isinstance(divisor, Duration):
            return self.to_nsec() / divisor.to_nsec()
        return Duration(0, int(round(self.to_nsec() / divisor)))


class Time(_TimeBase):
    """A point in (wall) time since the Unix epoch."""

    __slots__ = ()

    def __init__(self, secs: int | float = 0, nsecs: int = 0):
        super().__init__(secs, nsecs)
        if self.secs < 0:
            raise ValueError("Time cannot be negative")

    @classmethod
    def now(cls) -> "Time":
        return cls(0, _time.time_ns())

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


def get_time() -> float:
    """Current time in float seconds (rospy.get_time)."""
    return _time.time()


def get_rostime() -> Time:
    return Time.now()


_shutdown_event = threading.Event()


def _set_shutdown_event(event: threading.Event) -> None:
    """The node runtime hands over its shutdown event so sleeps wake up at shutdown."""
    global _shutdown_event
    _shutdown_event = event


def sleep(duration: float | Duration) -> None:
    """Sleep, but wake up and raise ``ROSInterruptException`` when the node shuts down."""
    from orchestra.node.exceptions import ROSInterruptException

    seconds = duration.to_sec() if isinstance(duration, Duration) else float(duration)
    if seconds <= 0:
        return
    if _shutdown_event.wait(seconds):
        raise ROSInterruptException("ROS shutdown request")


class Rate:
    """Keep a loop at ``hz`` iterations per second, absorbing the loop body's own time."""

    def __init__(self, hz: float, reset: bool = False):
        if hz <= 0:
            raise ValueError("Rate needs a positive frequency")
        self.period = 1.0 / hz
        self.reset = reset
        self._last = _time.monotonic()

    def remaining(self) -> Duration:
        return Duration.from_sec(self._last + self.period - _time.monotonic())

    def sleep(self) -> None:
        now = _time.monotonic()
        deadline = self._last + self.period
        if now > deadline + self.period:
            # fell far behind (or the clock jumped): restart the schedule instead of bursting
            deadline = now
        self._last = deadline
        sleep(deadline - now)
