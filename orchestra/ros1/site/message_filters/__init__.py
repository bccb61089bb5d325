"""message_filters for orchestra's ROS 1 layer: filters chained by ``registerCallback``.

``Subscriber`` feeds messages from a topic; ``Cache`` keeps the last N by stamp;
``TimeSynchronizer`` calls back with one message per input when all carry the same
``header.stamp``; ``ApproximateTimeSynchronizer`` when their stamps lie within ``slop``
seconds of each other. Stamps are ``header.stamp`` (``allow_headerless``: the arrival time).
"""
from __future__ import annotations

import bisect
import logging
import threading
from collections.abc import Callable
from typing import Any

from orchestra.node.rostime import Duration, Time
from orchestra.node.topics import Subscriber as _TopicSubscriber

__all__ = ["ApproximateTimeSynchronizer", "Cache", "SimpleFilter", "Subscriber",
           "TimeSynchronizer"]

log = logging.getLogger(__name__)


class SimpleFilter:
    """The callback registry every filter has: ``registerCallback(cb, *args)`` returns a
    connection id; ``signalMessage(*msgs)`` calls each ``cb(*msgs, *args)``."""

    def __init__(self) -> None:
        self.callbacks: dict[int, tuple[Callable, tuple]] = {}
        self._next_id = 0

    def registerCallback(self, cb: Callable, *args: Any) -> int:  # noqa: N802
        conn = self._next_id
        self._next_id += 1
        self.callbacks[conn] = (cb, args)
        return conn

    def signalMessage(self, *msg: Any) -> None:  # noqa: N802
        for cb, args in list(self.callbacks.values()):
            cb(*(msg + args))


class Subscriber(SimpleFilter):
    """A topic as a filter: ``Subscriber(topic, msg_class, queue_size=..., ...)`` takes
    rospy.Subscriber's arguments (``callback`` is the filter's)."""

    def __init__(self, *args: Any, **kwargs: Any):
        super().__init__()
        self.topic = args[0]
        kwargs.setdefault("queue_size", None)
        kwargs["callback"] = self.callback
        self.sub = _TopicSubscriber(*args, **kwargs)

    def callback(self, msg: Any) -> None:
        self.signalMessage(msg)

    def getTopic(self) -> str:  # noqa: N802
        return self.sub.resolved_name

    def unregister(self) -> None:
        self.sub.unregister()

    def __getattr__(self, key: str) -> Any:
        # rospy.Subscriber's other attributes (name, data_class...) as in message_filters
        if key == "sub":
            raise AttributeError(key)
        return getattr(self.sub, key)


def _stamp(msg: Any, allow_headerless: bool) -> Time | None:
    """``header.stamp``, the arrival time for a headerless message when allowed, else None."""
    header = getattr(msg, "header", None)
    if header is not None and hasattr(header, "stamp"):
        return header.stamp
    if allow_headerless:
        return Time.now()
    return None


class Cache(SimpleFilter):
    """The last ``cache_size`` messages from ``f``, ordered by stamp; each is passed on."""

    def __init__(self, f: SimpleFilter | None, cache_size: int = 1,
                 allow_headerless: bool = False):
        super().__init__()
        self.cache_size = cache_size
        self.allow_headerless = allow_headerless
        self.cache_msgs: list[Any] = []
        self.cache_times: list[Time] = []
        self._lock = threading.Lock()
        if f is not None:
            self.connectInput(f)

    def connectInput(self, f: SimpleFilter) -> None:  # noqa: N802
        self.incoming_connection = f.registerCallback(self.add)

    def add(self, msg: Any) -> None:
        stamp = _stamp(msg, self.allow_headerless)
        if stamp is None:
            log.warning("Cannot use message filters with non-stamped messages. Use the "
                        "'allow_headerless' constructor option to auto-assign ROS time to "
                        "headerless messages.")
            return
        with self._lock:
            at = bisect.bisect_right([t.to_nsec() for t in self.cache_times], stamp.to_nsec())
            self.cache_times.insert(at, stamp)
            self.cache_msgs.insert(at, msg)
            while len(self.cache_msgs) > self.cache_size:
                del self.cache_msgs[0]
                del self.cache_times[0]
        self.signalMessage(msg)

    def getInterval(self, from_stamp: Time, to_stamp: Time) -> list[Any]:  # noqa: N802
        """Messages stamped from ``from_stamp`` to ``to_stamp`` inclusive, oldest first."""
        with self._lock:
            return [m for m, t in zip(self.cache_msgs, self.cache_times, strict=True)
                    if from_stamp <= t <= to_stamp]

    def getElemAfterTime(self, stamp: Time) -> Any:  # noqa: N802
        """The oldest message stamped at or after ``stamp`` (None if none)."""
        with self._lock:
            return next((m for m, t in zip(self.cache_msgs, self.cache_times, strict=True) if t >= stamp),
                        None)

    def getElemBeforeTime(self, stamp: Time) -> Any:  # noqa: N802
        """The newest message stamped at or before ``stamp`` (None if none)."""
        with self._lock:
            found = [m for m, t in zip(self.cache_msgs, self.cache_times, strict=True) if t <= stamp]
        return found[-1] if found else None

    def getLastestTime(self) -> Time | None:  # noqa: N802 - message_filters' spelling
        with self._lock:
            return self.cache_times[-1] if self.cache_times else None

    getLatestTime = getLastestTime  # noqa: N815

    def getOldestTime(self) -> Time | None:  # noqa: N802
        with self._lock:
            return self.cache_times[0] if self.cache_times else None

    def getLast(self) -> Any:  # noqa: N802
        with self._lock:
            return self.cache_msgs[-1] if self.cache_msgs else None


class TimeSynchronizer(SimpleFilter):
    """One callback per set of messages, one from each filter in ``fs``, with the same
    stamp. At most ``queue_size`` stamps wait per input; the oldest are dropped."""

    def __init__(self, fs: list[SimpleFilter], queue_size: int, reset: bool = False):
        super().__init__()
        self.queue_size = queue_size
        self.reset = reset
        self._last_added = Time()
        self.lock = threading.Lock()
        self.queues: list[dict[int, Any]] = [{} for _ in fs]
        self.connectInput(fs)

    def connectInput(self, fs: list[SimpleFilter]) -> None:  # noqa: N802
        self.queues = [{} for _ in fs]
        self.input_connections = [f.registerCallback(self.add, q, i)
                                  for i, (f, q) in enumerate(zip(fs, self.queues, strict=True))]

    def _check_reset(self) -> None:
        """``reset``: ROS time jumped back (a restarted bag or simulator): forget the queues."""
        now = Time.now()
        if self.reset and now < self._last_added:
            for q in self.queues:
                q.clear()
        self._last_added = now

    def add(self, msg: Any, my_queue: dict[int, Any], my_queue_index: int | None = None) -> None:
        stamp = _stamp(msg, False)
        if stamp is None:
            log.warning("TimeSynchronizer needs messages with a header.stamp")
            return
        key = stamp.to_nsec()
        with self.lock:
            self._check_reset()
            my_queue[key] = msg
            while len(my_queue) > self.queue_size:
                del my_queue[min(my_queue)]
            common = set.intersection(*(set(q) for q in self.queues))
            if not common:
                return
            newest = max(common)
            msgs = [q[newest] for q in self.queues]
            for q in self.queues:  # what is older can never complete a set any more
                for old in [k for k in q if k <= newest]:
                    del q[old]
        self.signalMessage(*msgs)


class ApproximateTimeSynchronizer(TimeSynchronizer):
    """One callback per set of messages whose stamps all lie within ``slop`` seconds of each
    other. ``allow_headerless`` stamps headerless messages with their arrival time; ``reset``
    empties the queues when ROS time jumps backwards (a restarted bag or simulator)."""

    def __init__(self, fs: list[SimpleFilter], queue_size: int, slop: float,
                 allow_headerless: bool = False, reset: bool = False):
        super().__init__(fs, queue_size, reset)
        self.slop = Duration.from_sec(slop).to_nsec()
        self.allow_headerless = allow_headerless

    def add(self, msg: Any, my_queue: dict[int, Any], my_queue_index: int | None = None) -> None:
        stamp = _stamp(msg, self.allow_headerless)
        if stamp is None:
            log.warning("Cannot use message filters with non-stamped messages. Use the "
                        "'allow_headerless' constructor option to auto-assign ROS time to "
                        "headerless messages.")
            return
        key = stamp.to_nsec()
        with self.lock:
            self._check_reset()
            my_queue[key] = msg
            while len(my_queue) > self.queue_size:
                del my_queue[min(my_queue)]
            chosen = self._match(key)
            if chosen is None:
                return
            msgs = [q[k] for q, k in zip(self.queues, chosen, strict=True)]
            for q, k in zip(self.queues, chosen, strict=True):
                for old in [s for s in q if s <= k]:
                    del q[old]
        self.signalMessage(*msgs)

    def _match(self, key: int) -> list[int] | None:
        """For the new stamp ``key``: the stamp closest to it in every queue, if all of
        those lie within ``slop`` of each other."""
        chosen = []
        for q in self.queues:
            if not q:
                return None
            chosen.append(min(q, key=lambda s: abs(s - key)))
        return chosen if max(chosen) - min(chosen) <= self.slop else None
