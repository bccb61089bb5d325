"""Outgoing calls from the master to node slave APIs: asynchronous, ordered per node.

rosmaster must never block a registration on a slow or dead subscriber, yet a node has to
see its ``publisherUpdate``s in the order the master decided them (otherwise a stale
publisher list could arrive last). So each target URI gets its own FIFO drained by one
worker thread at a time: calls to one node are serial, calls to different nodes run in
parallel, and an idle node costs no thread. Workers that drained their node wait a while
for the next one instead of exiting: starting a thread (~0.1 ms, and the caller waits until
it runs) on the request path, once per subscriber, was most of a registerPublisher on a
topic with subscribers. A new thread is started only when every worker is busy (a hung
node keeps its worker, never the others).
"""
from __future__ import annotations

import logging
import queue
import threading
from collections import deque
from typing import Any

from orchestra.rpc import proxy as rpc_proxy

log = logging.getLogger(__name__)

MASTER_CALLER_ID = "/master"


class Notifier:
    """Per-URI FIFO queues of XML-RPC calls, each drained by one worker thread at a time."""

    IDLE_SECONDS = 30.0  # how long a worker waits for another node before it exits

    def __init__(self, timeout: float = 10.0):
        self.timeout = timeout
        self._queues: dict[str, deque[tuple[str, tuple[Any, ...]]]] = {}
        self._lock = threading.Lock()
        self._idle = threading.Condition(self._lock)
        self._closed = False
        self._handoff: queue.SimpleQueue[str | None] = queue.SimpleQueue()
        self._waiting = 0  # workers waiting on _handoff (counted under _lock)

    def send(self, api: str, method: str, *args: Any) -> None:
        """Queue ``api.method(*args)``; returns at once."""
        with self._lock:
            if self._closed:
                return
            pending = self._queues.get(api)
            if pending is not None:
                pending.append((method, args))
                return
            self._queues[api] = deque([(method, args)])
            if self._waiting:  # a waiting worker takes this node
                self._waiting -= 1
                self._handoff.put(api)
                return
        threading.Thread(target=self._work, args=(api,), daemon=True,
                         name="master notify").start()

    def _work(self, api: str | None) -> None:
        """Drain nodes' queues one after the other, then wait for the next node a while."""
        while api is not None and self._drain(api):
            try:
                api = self._handoff.get(timeout=self.IDLE_SECONDS)
            except queue.Empty:
                with self._lock:  # a node handed over just as the wait ended is still ours
                    try:
                        api = self._handoff.get_nowait()
                    except queue.Empty:
                        self._waiting -= 1
                        return

    def _drain(self, api: str) -> bool:
        """Make the queued calls to ``api``; True when this worker, now idle, was counted as
        waiting for another node (in the same step that emptied the queue, so a ``send``
        right after ``wait_idle`` finds it), False once the notifier is closed."""
        proxy = rpc_proxy(api, self.timeout)
        try:
            while True:
                with self._lock:
                    pending = self._queues[api]
                    if not pending or self._closed:
                        del self._queues[api]
                        self._idle.notify_all()
                        if self._closed:
                            return False
                        self._waiting += 1
                        return True
                    method, args = pending.popleft()
                try:
                    getattr(proxy, method)(*args)
                except Exception as exc:  # a dead node must not stop the master
                    log.info("%s(%s) to %s failed: %s", method, args[1:2], api, exc)
        finally:
            proxy("close")()

    def wait_idle(self, timeout: float | None = None) -> bool:
        """Block until every queued call was made (tests and orderly shutdown use this)."""
        with self._lock:
            return self._idle.wait_for(lambda: not self._queues, timeout)

    def close(self) -> None:
        """Drop queued calls and let waiting workers go; calls in flight finish on their
        own (daemon threads)."""
        with self._lock:
            self._closed = True
            for pending in self._queues.values():
                pending.clear()
            for _ in range(self._waiting):
                self._handoff.put(None)
            self._waiting = 0
