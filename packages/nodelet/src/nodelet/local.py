"""In-process delivery between nodelets of one manager (roscpp's intra-process path).

Nodelets exist so that nodes sharing a process pass messages without the network. Here a
nodelet's publisher also hands each message straight to the subscriptions of other
nodelets in the same process on the same (resolved) topic, while TCPROS still serves every
subscriber outside the process. ``orchestra.node`` also hands a process its own publications
(as rospy does); a nodelet's subscription drops those TCPROS copies (``base.from_other_process``)
so a message reaches an in-process nodelet exactly once, through this bus.

Delivery is asynchronous, one worker thread per local subscription with a ``queue_size``
bound (oldest dropped), like a subscriber's receive thread: a slow callback never blocks the
publisher or the other nodelets. Messages are shared, not copied; treat them as read-only
(roscpp passes ``ConstPtr`` for the same reason).
"""
from __future__ import annotations

import collections
import logging
import threading
from collections.abc import Callable
from typing import Any

log = logging.getLogger(__name__)


class LocalSubscription:
    def __init__(self, bus: LocalBus, topic: str, msg_type: str,
                 callback: Callable[[Any], None], queue_size: int):
        self.bus, self.topic, self.msg_type, self.callback = bus, topic, msg_type, callback
        self._queue: collections.deque = collections.deque(maxlen=max(1, queue_size or 1))
        self._cond = threading.Condition()
        self._closed = False
        self._thread = threading.Thread(target=self._run, daemon=True, name=f"local:{topic}")
        self._thread.start()

    def offer(self, msg: Any) -> None:
        with self._cond:
            if not self._closed:
                self._queue.append(msg)
                self._cond.notify()

    def _run(self) -> None:
        while True:
            with self._cond:
                while not self._queue and not self._closed:
                    self._cond.wait()
                if self._closed:
                    return
                msg = self._queue.popleft()
            try:
                self.callback(msg)
            except Exception:  # a faulty callback must not stop delivery
                log.exception("callback for %s failed", self.topic)

    def unregister(self) -> None:
        self.bus._remove(self)
        with self._cond:
            self._closed = True
            self._cond.notify()


class LocalBus:
    """Topic -> in-process subscriptions, plus the last message of latched publishers."""

    def __init__(self) -> None:
        self._subs: dict[str, list[LocalSubscription]] = {}
        self._latched: dict[str, Any] = {}
        self._lock = threading.Lock()

    def subscribe(self, topic: str, msg_type: str, callback: Callable[[Any], None],
                  queue_size: int = 10) -> LocalSubscription:
        sub = LocalSubscription(self, topic, msg_type, callback, queue_size)
        with self._lock:
            self._subs.setdefault(topic, []).append(sub)
            latched = self._latched.get(topic)
        if latched is not None and getattr(latched, "_type", None) == msg_type:
            sub.offer(latched)
        return sub

    def publish(self, topic: str, msg: Any, latch: bool = False) -> int:
        """Hand ``msg`` to every local subscription of ``topic``; how many took it."""
        with self._lock:
            subs = list(self._subs.get(topic, ()))
            if latch:
                self._latched[topic] = msg
        msg_type = getattr(msg, "_type", None)
        taken = 0
        for sub in subs:
            if sub.msg_type == msg_type:
                sub.offer(msg)
                taken += 1
        return taken

    def count(self, topic: str) -> int:
        with self._lock:
            return len(self._subs.get(topic, ()))

    def forget_latched(self, topic: str) -> None:
        with self._lock:
            self._latched.pop(topic, None)

    def _remove(self, sub: LocalSubscription) -> None:
        with self._lock:
            subs = self._subs.get(sub.topic, [])
            if sub in subs:
                subs.remove(sub)


BUS = LocalBus()


class NodeletPublisher:
    """A publisher that reaches in-process nodelets directly and the rest over TCPROS."""

    def __init__(self, remote: Any, topic: str, latch: bool, bus: LocalBus = BUS):
        self.remote, self.topic, self.latch, self.bus = remote, topic, latch, bus
        self.data_class = getattr(remote, "data_class", None)

    def publish(self, *args: Any, **kwargs: Any) -> None:
        if len(args) == 1 and not kwargs and hasattr(args[0], "_type"):
            msg = args[0]
        else:
            msg = self.data_class(*args, **kwargs)
        if self.remote is not None:
            self.remote.publish(msg)
        self.bus.publish(self.topic, msg, self.latch)

    def get_num_connections(self) -> int:
        remote = self.remote.get_num_connections() if self.remote is not None else 0
        return remote + self.bus.count(self.topic)

    def unregister(self) -> None:
        if self.latch:
            self.bus.forget_latched(self.topic)
        if self.remote is not None:
            self.remote.unregister()
