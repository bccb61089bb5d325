"""A minimal single-threaded event loop: file descriptors ready + timers, nothing else.

Why not a 10 Hz poll loop like roslaunch: every child is watched through a pidfd (readable
the moment the child exits) and its pipes, so the supervisor sleeps in ``select`` until
something really happens, reacts at once (crash -> respawn in milliseconds), and costs no CPU
while nodes are idle. Why not asyncio: the loop needs no coroutines, and its startup cost and
indirection buy nothing here.
"""
from __future__ import annotations

import heapq
import itertools
import logging
import os
import selectors
import threading
import time
from collections.abc import Callable

logger = logging.getLogger(__name__)


class Timer:
    """A scheduled callback; ``cancel()`` makes it a no-op."""

    __slots__ = ("deadline", "callback", "cancelled")

    def __init__(self, deadline: float, callback: Callable[[], None]):
        self.deadline = deadline
        self.callback = callback
        self.cancelled = False

    def cancel(self) -> None:
        self.cancelled = True


class EventLoop:
    def __init__(self) -> None:
        self._selector = selectors.DefaultSelector()
        self._timers: list[tuple[float, int, Timer]] = []
        self._seq = itertools.count()
        self._pending: list[Callable[[], None]] = []
        self._lock = threading.Lock()
        self._wake_r, self._wake_w = os.pipe()
        os.set_blocking(self._wake_r, False)
        os.set_blocking(self._wake_w, False)
        self.add_reader(self._wake_r, self._run_pending)

    def call_threadsafe(self, callback: Callable[[], None]) -> None:
        """Run ``callback`` in the loop's thread soon (the only entry point for other threads)."""
        with self._lock:
            self._pending.append(callback)
        try:
            os.write(self._wake_w, b"x")
        except (BlockingIOError, OSError):
            pass

    def _run_pending(self) -> None:
        try:
            os.read(self._wake_r, 4096)
        except (BlockingIOError, OSError):
            pass
        with self._lock:
            pending, self._pending = self._pending, []
        for callback in pending:
            callback()

    def add_reader(self, fd: int, callback: Callable[[], None]) -> None:
        self._selector.register(fd, selectors.EVENT_READ, callback)

    def remove_reader(self, fd: int) -> None:
        try:
            self._selector.unregister(fd)
        except (KeyError, ValueError):
            pass

    def call_later(self, delay: float, callback: Callable[[], None]) -> Timer:
        timer = Timer(time.monotonic() + max(0.0, delay), callback)
        heapq.heappush(self._timers, (timer.deadline, next(self._seq), timer))
        return timer

    def _next_timeout(self, limit: float | None) -> float | None:
        while self._timers and self._timers[0][2].cancelled:
            heapq.heappop(self._timers)
        timeout = limit
        if self._timers:
            wait = max(0.0, self._timers[0][0] - time.monotonic())
            timeout = wait if timeout is None else min(timeout, wait)
        return timeout

    def run_once(self, limit: float | None = None) -> None:
        """Wait for the next fd event or due timer (at most ``limit`` s) and dispatch it."""
        timeout = self._next_timeout(limit)
        try:
            events = self._selector.select(timeout)
        except InterruptedError:
            events = []
        registered = self._selector.get_map()
        for key, _mask in events:
            # an earlier callback of this batch may have unregistered (and closed) this fd
            if registered.get(key.fd) is key:
                key.data()
        now = time.monotonic()
        while self._timers and self._timers[0][0] <= now:
            _, _, timer = heapq.heappop(self._timers)
            if not timer.cancelled:
                timer.cancelled = True
                timer.callback()

    def close(self) -> None:
        self._selector.close()
        for fd in (self._wake_r, self._wake_w):
            try:
                os.close(fd)
            except OSError:
                pass
