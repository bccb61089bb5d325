"""``bag play``: publish the messages of bags with their recorded timing.

Each topic is advertised with the type, md5sum and definition its bag connection carries
(raw bytes go out unchanged, nothing is decoded), latched when the recording publisher was
latched. Bag time maps to wall time as ``wall = start + (stamp - first) / rate``; pausing
moves ``start`` forward by the time spent paused. ``/clock`` carries the bag time for nodes
under ``/use_sim_time``.
"""
from __future__ import annotations

import heapq
import logging
import threading
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field

from orchestra.bag.reader import BagReader
from orchestra.bag.records import BagFormatError, Connection

log = logging.getLogger(__name__)

NS = 1_000_000_000
#: --wait-for-subscribers: how long to wait for more subscribers once each topic has one
LATE_SUBSCRIBERS = 3.0


@dataclass
class PlayOptions:
    rate: float = 1.0
    start: float = 0.0  # -s: seconds into the bag
    duration: float | None = None  # -u
    loop: bool = False
    clock: bool = False
    hz: float = 100.0
    topics: list[str] | None = None
    pause: bool = False
    delay: float = 0.2  # -d: rosbag's advertise sleep
    immediate: bool = False
    queue_size: int = 100
    wait_for_subscribers: bool = False


@dataclass
class PlayState:
    """What the progress line shows; changed by the keyboard."""

    paused: bool = False
    step: int = 0
    bag_time: int = 0
    first: int = 0
    last: int = 0
    published: int = 0
    done: bool = False
    lock: threading.Lock = field(default_factory=threading.Lock)

    def toggle_pause(self) -> None:
        with self.lock:
            self.paused = not self.paused

    def request_step(self) -> None:
        with self.lock:
            if self.paused:
                self.step += 1


def raw_class(conn: Connection) -> type:
    """A message class that publishes ``conn``'s raw bytes under its type, md5 and
    definition (a subscriber checks those in the connection header)."""
    from orchestra.node.msg import AnyMsg
    return type("BagRaw", (AnyMsg,), {"__slots__": (), "_type": conn.type,
                                       "_md5sum": conn.md5sum,
                                       "_full_text": conn.definition})


def merged(readers: list[BagReader], topics: list[str] | None, start: int | None,
           end: int | None) -> Iterator[tuple[Connection, int, bytes]]:
    """The messages of several bags in one time order."""
    streams = [((stamp, i, n, conn, data) for n, (conn, stamp, data)
                in enumerate(r.messages(topics, start, end))) for i, r in enumerate(readers)]
    for stamp, _i, _n, conn, data in heapq.merge(*streams, key=lambda m: m[:3]):
        yield conn, stamp, data


class Player:
    """Publishes bags; ``run()`` blocks until done or ``stop()``."""

    def __init__(self, readers: list[BagReader], opts: PlayOptions,
                 sleep: Callable[[float], None] = time.sleep):
        self.opts = opts
        self.readers = readers
        self.state = PlayState(paused=opts.pause)
        self.stopped = threading.Event()
        self.error: BagFormatError | None = None
        self._sleep = sleep
        self._pubs: dict[str, tuple[object, str]] = {}
        self._clock_pub: object | None = None
        self._clock_cls: type | None = None
        self._last_clock = 0.0
        starts = [r.start_time for r in self.readers if r.chunk_infos]
        ends = [r.end_time for r in self.readers if r.chunk_infos]
        self.state.first = min(starts, default=0)
        self.state.last = max(ends, default=0)

    def close(self) -> None:
        for reader in self.readers:
            reader.close()

    def stop(self) -> None:
        self.stopped.set()

    # --- publishing -------------------------------------------------------------------------

    def advertise(self) -> None:
        import orchestra.node as rospy
        wanted = set(self.opts.topics) if self.opts.topics else None
        for reader in self.readers:
            for conn in reader.connections:
                if wanted is not None and conn.topic not in wanted:
                    continue
                known = self._pubs.get(conn.topic)
                if known is not None:
                    if known[1] != conn.md5sum:
                        log.warning("%s has several types in the bags; playing %s only",
                                    conn.topic, conn.type)
                    continue
                pub = rospy.Publisher(conn.topic, raw_class(conn), queue_size=self.opts.queue_size,
                                      latch=conn.latching)
                self._pubs[conn.topic] = (pub, conn.md5sum)
        if self.opts.clock:
            self._clock_cls = rospy.get_message_class("rosgraph_msgs/Clock")
            self._clock_pub = rospy.Publisher("/clock", self._clock_cls, queue_size=1)
        if self.opts.wait_for_subscribers:
            self._wait_for_subscribers()
        if self.opts.delay > 0:
            self.stopped.wait(self.opts.delay)

    def _wait_for_subscribers(self) -> None:
        """Wait until every topic has a subscriber (rosbag's rule), then up to
        ``LATE_SUBSCRIBERS`` seconds more for the other subscribers the master listed when
        play started, so a second subscriber does not miss the first messages (a listed
        subscriber that died without unregistering cannot make play wait forever)."""
        from orchestra.node.runtime import get_runtime
        _pubs, subs, _srvs = get_runtime().master.call("getSystemState")
        listed = {topic: len(nodes) for topic, nodes in subs}
        for pub, _md5 in self._pubs.values():
            while pub.get_num_connections() < 1:  # type: ignore[attr-defined]
                if self.stopped.wait(0.01):
                    return
        deadline = time.monotonic() + LATE_SUBSCRIBERS
        for topic, (pub, _md5) in self._pubs.items():
            while pub.get_num_connections() < listed.get(topic, 0):  # type: ignore[attr-defined]
                if time.monotonic() > deadline:
                    log.warning("%s: not every listed subscriber connected", topic)
                    break
                if self.stopped.wait(0.01):
                    return

    def _publish(self, conn: Connection, data: bytes) -> None:
        entry = self._pubs.get(conn.topic)
        if entry is None or entry[1] != conn.md5sum:
            return
        pub = entry[0]
        pub.publish(pub.data_class(data))  # type: ignore[attr-defined]
        self.state.published += 1

    def _publish_clock(self, stamp: int) -> None:
        if self._clock_pub is None or self._clock_cls is None:
            return
        from orchestra.node.rostime import Time
        msg = self._clock_cls()
        msg.clock = Time(stamp // NS, stamp % NS)
        self._clock_pub.publish(msg)  # type: ignore[attr-defined]

    # --- timing -----------------------------------------------------------------------------

    def run(self) -> None:
        """Play (a damaged chunk met on the way ends playback; ``error`` says why)."""
        try:
            self._run()
        except BagFormatError as exc:
            self.error = exc
        finally:
            self.state.done = True

    def _run(self) -> None:
        opts = self.opts
        first = self.state.first + int(opts.start * NS)
        end = None if opts.duration is None else first + int(opts.duration * NS)
        while not self.stopped.is_set():
            self._play_once(first, end)
            if not opts.loop or self.stopped.is_set():
                break

    def _play_once(self, first: int, end: int | None) -> None:
        opts = self.opts
        wall_start = -1.0
        for conn, stamp, data in merged(self.readers, opts.topics, first, end):
            if self.stopped.is_set():
                return
            if wall_start < 0:
                # the timeline starts when the first message is at hand (not before reading
                # its chunk), so the first one is not late relative to all the others
                wall_start = time.monotonic() - (stamp - first) / NS / opts.rate
            if not opts.immediate:
                wall_start = self._wait_until(wall_start, first, stamp)
                if wall_start < 0:
                    return
            self.state.bag_time = stamp
            self._publish(conn, data)

    def _wait_until(self, wall_start: float, first: int, stamp: int) -> float:
        """Sleep until ``stamp``'s wall time (publishing /clock meanwhile), honouring
        pause and step; returns the (possibly shifted) wall start, -1 when stopped."""
        opts = self.opts
        clock_period = 1.0 / opts.hz if opts.clock and opts.hz > 0 else None
        while True:
            if self.stopped.is_set():
                return -1
            with self.state.lock:
                paused = self.state.paused
                stepping = paused and self.state.step > 0
                if stepping:
                    self.state.step -= 1
            if stepping:
                # a step publishes the next message now and shifts the timeline to it
                return time.monotonic() - (stamp - first) / NS / opts.rate
            if paused:
                pause_began = time.monotonic()
                self._sleep(0.02)
                wall_start += time.monotonic() - pause_began
                continue
            now = time.monotonic()
            target = wall_start + (stamp - first) / NS / opts.rate
            if clock_period is not None and now - self._last_clock >= clock_period:
                self._last_clock = now
                bag_now = first + int((now - wall_start) * opts.rate * NS)
                self._publish_clock(min(bag_now, stamp))
            remaining = target - now
            if remaining <= 0:
                return wall_start
            nap = remaining if clock_period is None else min(remaining, clock_period)
            self._sleep(min(nap, 0.1))
