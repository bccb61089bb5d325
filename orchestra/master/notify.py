"""Outgoing calls from the master to node slave APIs: asynchronous, ordered per node.

rosmaster must never block a registration on a slow or dead subscriber, yet a node has to
see its ``publisherUpdate``s in the order the master decided them (otherwise a stale
publisher list could arrive last). So each target URI gets its own FIFO drained by one
short-lived thread: calls to one node are serial, calls to different nodes run in parallel,
and an idle node costs no thread.
"""
from __future__ import annotations

import logging
import threading
from collections import deque
from typing import Any

from orchestra.rpc import proxy as rpc_proxy

log = logging.getLogger(__name__)

MASTER_CALLER_ID = "/master"


class Notifier:
    """Per-URI FIFO queues of XML-RPC calls, each drained by its own worker thread."""

    def __init__(self, timeout: float = 10.0):
        self.timeout = timeout
        self._queues: dict[str, deque[tuple[str, tuple[Any, ...]]]] = {}
        self._lock = threading.Lock()
        self._idle = threading.Condition(self._lock)
        self._closed = False

    def send(self, api: str, method: str, *args: Any) -> None:
        """Queue ``api.method(*args)``; returns at once."""
        with self._lock:
            if self._closed:
                return
            queue = self._queues.get(api)
            if queue is not None:
                queue.append((method, args))
                return
            self._queues[api] = deque([(method, args)])
        threading.Thread(target=self._drain, args=(api,), daemon=True,
                         name=f"notify {api}").start()

    def _drain(self, api: str) -> None:
        proxy = rpc_proxy(api, self.timeout)
        try:
            while True:
                with self._lock:
                    queue = self._queues[api]
                    if not queue or self._closed:
                        del self._queues[api]
                        self._idle.notify_all()
                        return
                    method, args = queue.popleft()
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
        """Drop queued calls; calls in flight finish on their own (daemon threads)."""
        with self._lock:
            self._closed = True
            for queue in self._queues.values():
                queue.clear()
