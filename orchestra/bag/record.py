"""``bag record``: subscribe as a node to raw topics and write what arrives into bags.

The subscriptions are raw (``AnyMsg``): nothing is decoded, and the publisher's connection
header (type, md5sum, definition, callerid, latching) is stored per connection as rosbag
record stores it. Messages travel from the receive threads through one bounded queue
(``--buffsize``; the oldest is dropped when full, as rosbag does) to one writer thread,
which writes chunk by chunk into ``NAME.bag.active`` and renames it to ``NAME.bag`` when the
bag is complete. ``-a``/``-e`` poll the master, so topics that appear later are recorded.
"""
from __future__ import annotations

import collections
import logging
import os
import re
import threading
import time
from dataclasses import dataclass, field

from orchestra.bag.writer import DEFAULT_CHUNK_SIZE, BagWriteError, BagWriter

log = logging.getLogger(__name__)

#: how often -a / -e ask the master for new topics
DISCOVERY_PERIOD = 0.25

#: messages up to this size are written by the thread that received them when the writer is
#: idle; larger ones always go to the writer thread (see ``Recorder._on_message``)
DIRECT_WRITE_MAX = 64 * 1024


class RecordError(Exception):
    """Recording cannot start or cannot go on (no folder, disk full)."""


@dataclass
class RecordOptions:
    topics: list[str] = field(default_factory=list)
    all: bool = False
    regex: str | None = None
    exclude: str | None = None
    name: str | None = None  # -O
    prefix: str | None = None  # -o
    duration: float | None = None
    split_size: int | None = None  # bytes
    split_duration: float | None = None  # seconds
    compression: str = "none"
    buffsize: int = 256 * 1024 * 1024
    chunksize: int = DEFAULT_CHUNK_SIZE
    limit: int | None = None
    node_name: str = "record"


def bag_path(opts: RecordOptions, started: float, index: int | None) -> str:
    """The file name rosbag record would use: ``-O NAME`` as given (``.bag`` added),
    ``-o PREFIX`` plus ``_YYYY-MM-DD-HH-MM-SS``, the bare stamp without either; ``_N``
    before ``.bag`` for the N-th part of a split recording."""
    stamp = time.strftime("%Y-%m-%d-%H-%M-%S", time.localtime(started))
    if opts.name:
        base = opts.name[:-4] if opts.name.endswith(".bag") else opts.name
    elif opts.prefix:
        prefix = opts.prefix[:-4] if opts.prefix.endswith(".bag") else opts.prefix
        base = prefix + stamp if prefix.endswith("/") else f"{prefix}_{stamp}"
    else:
        base = stamp
    return f"{base}_{index}.bag" if index is not None else base + ".bag"


def check_folder(path: str) -> None:
    folder = os.path.dirname(os.path.abspath(path))
    if not os.path.isdir(folder):
        raise RecordError(f"cannot record to {path}: folder {folder} does not exist")
    if not os.access(folder, os.W_OK):
        raise RecordError(f"cannot record to {path}: folder {folder} is not writable")


class Recorder:
    """One recording: start(), then stop() (or wait until it stops by itself)."""

    def __init__(self, opts: RecordOptions):
        self.opts = opts
        self.started = time.time()
        self.split_index: int | None = 0 if (opts.split_size or opts.split_duration) else None
        self.path = bag_path(opts, self.started, self.split_index)
        check_folder(self.path)
        self._include = re.compile(opts.regex) if opts.regex else None
        self._exclude = re.compile(opts.exclude) if opts.exclude else None
        self._queue: collections.deque = collections.deque()
        self._queued_bytes = 0
        self._cond = threading.Condition()
        self._write_lock = threading.Lock()
        self.stopping = threading.Event()
        self.error: str | None = None
        self.messages = 0
        self.bytes = 0
        self.dropped = 0
        self.files: list[str] = []
        self._counts: dict[str, int] = {}
        self._subscribed: dict[str, object] = {}
        self._named: list[str] = []  # the topics named on the command line, resolved
        self._writer: BagWriter | None = None
        self._part_started = 0.0
        self._threads: list[threading.Thread] = []

    # --- running ----------------------------------------------------------------------------

    def start(self) -> None:
        import orchestra.node as rospy
        self._open_part()
        rospy.init_node(self.opts.node_name, argv=[], anonymous=True, disable_signals=True,
                        disable_rosout=True)
        self._named = [rospy.resolve_name(topic) for topic in self.opts.topics]
        for topic in self._named:
            self._subscribe(topic)
        self._spawn(self._write_loop, "bag-writer")
        if self.opts.all or self._include is not None:
            self._spawn(self._discover_loop, "bag-discovery")

    def _spawn(self, target, name: str) -> None:
        thread = threading.Thread(target=target, name=name, daemon=True)
        thread.start()
        self._threads.append(thread)

    def wait(self, timeout: float | None = None) -> bool:
        """Wait for a reason to stop (duration, limit, error); True when there is one."""
        deadline = None if self.opts.duration is None else self.started + self.opts.duration
        if deadline is not None:
            remaining = deadline - time.time()
            if timeout is None or remaining < timeout:
                if self.stopping.wait(max(0.0, remaining)):
                    return True
                self.stopping.set()
                return True
        return self.stopping.wait(timeout)

    def stop(self) -> None:
        """Unsubscribe, write what is queued, close the bag (renaming it to its name)."""
        from orchestra.node import runtime
        self.stopping.set()
        runtime.reset("bag record done")
        with self._cond:
            self._cond.notify_all()
        for thread in self._threads:
            thread.join()
        with self._write_lock:
            self._close_part()

    # --- subscriptions ----------------------------------------------------------------------

    def _wanted(self, topic: str) -> bool:
        if self._exclude is not None and self._exclude.fullmatch(topic):
            return False
        if self.opts.all:
            return True
        return self._include is not None and bool(self._include.fullmatch(topic))

    def _discover_loop(self) -> None:
        import orchestra.node as rospy
        while not self.stopping.is_set():
            try:
                topics = rospy.get_published_topics()
            except Exception as exc:  # the master went away for a moment: try again
                log.debug("cannot list topics: %s", exc)
                topics = []
            for topic, _type in topics:
                if topic not in self._subscribed and self._wanted(topic):
                    self._subscribe(topic)
            self.stopping.wait(DISCOVERY_PERIOD)

    def _subscribe(self, topic: str) -> None:
        import orchestra.node as rospy
        from orchestra.node.msg import AnyMsg
        if topic in self._subscribed:
            return
        log.info("subscribing to %s", topic)
        self._subscribed[topic] = rospy.Subscriber(
            topic, AnyMsg, self._on_message, callback_args=topic, queue_size=0)

    def _on_message(self, msg, topic: str) -> None:
        """A receive thread: stamp, then write a small message at once when nothing is
        queued and nobody is writing (no hand-over to another thread: what makes small
        messages fast), else queue for the writer thread. A large one (an image) always
        goes to the writer: its file write (a few ms when the page cache is busy) then
        runs while this thread receives the next one, as rosbag record's writer thread
        does, instead of holding up the socket. Order is kept: the writer thread takes the
        write lock before it takes a batch, and a direct write needs an empty queue."""
        from orchestra.node.rostime import get_rostime
        stamp = get_rostime().to_nsec()
        data = msg._buff
        with self._cond:
            if self.stopping.is_set():
                return
            direct = (len(data) < DIRECT_WRITE_MAX and not self._queue
                      and self._write_lock.acquire(blocking=False))
            if not direct:
                self._enqueue((stamp, topic, msg._connection_header, data))
                return
        try:
            if self._writer is not None:
                self._write(stamp, topic, msg._connection_header, data)
        except BagWriteError as exc:
            self.error = str(exc)
            self.stopping.set()
        finally:
            self._write_lock.release()

    def _enqueue(self, item: tuple) -> None:
        """Queue for the writer thread (``_cond`` held); beyond --buffsize the oldest go."""
        self._queue.append(item)
        self._queued_bytes += len(item[3])
        while self._queued_bytes > self.opts.buffsize and len(self._queue) > 1:
            old = self._queue.popleft()
            self._queued_bytes -= len(old[3])
            self.dropped += 1
            log.warning("bag record buffer exceeded: dropping the oldest queued message")
        self._cond.notify()

    # --- writing ----------------------------------------------------------------------------

    def _write_loop(self) -> None:
        while True:
            with self._cond:
                while not self._queue and not self.stopping.is_set():
                    self._cond.wait(0.5)
                    with self._write_lock:
                        self._maybe_split_idle()
                if not self._queue and self.stopping.is_set():
                    return
            with self._write_lock:
                with self._cond:
                    batch = list(self._queue)
                    self._queue.clear()
                    self._queued_bytes = 0
                try:
                    for item in batch:
                        self._write(*item)
                except BagWriteError as exc:
                    self.error = str(exc)
                    self.stopping.set()
                    return

    def _write(self, stamp: int, topic: str, header: dict[str, str], data: bytes) -> None:
        limit = self.opts.limit
        if limit is not None:
            seen = self._counts.get(topic, 0)
            if seen >= limit:
                return
            self._counts[topic] = seen + 1
            if seen + 1 == limit and not (self.opts.all or self._include) and all(
                    self._counts.get(t, 0) >= limit for t in self._named):
                self.stopping.set()
        writer = self._writer
        assert writer is not None
        conn = writer.add_connection(topic, {k: v for k, v in header.items() if k != "error"})
        writer.write(conn, stamp, data)
        self.messages += 1
        self.bytes += len(data)
        self._maybe_split()

    def _maybe_split(self) -> None:
        writer = self._writer
        assert writer is not None
        if self.opts.split_size and writer.size >= self.opts.split_size:
            self._next_part()
        elif self.opts.split_duration and time.time() - self._part_started >= \
                self.opts.split_duration:
            self._next_part()

    def _maybe_split_idle(self) -> None:
        if self.opts.split_duration and self._writer is not None and self._writer.messages and \
                time.time() - self._part_started >= self.opts.split_duration:
            self._next_part()

    def _next_part(self) -> None:
        self._close_part()
        assert self.split_index is not None
        self.split_index += 1
        self.path = bag_path(self.opts, self.started, self.split_index)
        self._open_part()

    def _open_part(self) -> None:
        try:
            self._writer = BagWriter(self.path + ".active", self.opts.compression,
                                     self.opts.chunksize).open()
        except BagWriteError as exc:
            raise RecordError(str(exc)) from None
        self._part_started = time.time()

    def _close_part(self) -> None:
        writer, self._writer = self._writer, None
        if writer is None:
            return
        try:
            writer.close()
        except BagWriteError as exc:
            self.error = str(exc)
        if os.path.exists(writer.path):
            os.replace(writer.path, self.path)
            self.files.append(self.path)
