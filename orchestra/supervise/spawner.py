"""Starting many processes at once: a few threads, each waiting for one child's exec.

Why: ``subprocess.Popen`` returns only once its child has exec'd (vfork: the parent is
suspended until then). On a busy machine a new child waits for a CPU behind everything
already runnable -- typically the nodes started just before it, each busy starting its own
interpreter -- so starting 100 nodes one after the other paid that scheduling wait 100 times
(~9 ms each on 2 loaded cores, for ~0.6 ms of our own work). Several spawns in flight pay it
once per batch. Python releases the GIL while it waits for the vfork'ed child, so threads do
overlap here.

The threads live until ``close()``: the kernel sends a child its parent-death signal
(``PR_SET_PDEATHSIG``, how a node dies with orchestra) when the *thread* that forked it
ends, not the process. So a spawner must outlive every process it started.
"""
from __future__ import annotations

import functools
import queue
import threading
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Generic, TypeVar

T = TypeVar("T")

#: at most this many spawns in flight (threads are made on first need, up to this many)
MAX_THREADS = 100


@dataclass
class Outcome(Generic[T]):
    """What one call returned, or the exception it raised."""

    value: T | None = None
    error: BaseException | None = None


class Spawner:
    """Runs calls (each one ``Popen``) on long-lived threads; see the module docstring."""

    def __init__(self, max_threads: int = MAX_THREADS, name: str = "spawn") -> None:
        self.max_threads = max_threads
        self._name = name
        self._work: queue.SimpleQueue[Callable[[], None] | None] = queue.SimpleQueue()
        self._threads: list[threading.Thread] = []

    def run(self, calls: Sequence[Callable[[], T]]) -> list[Outcome[T]]:
        """Run every call, up to ``max_threads`` at once; their outcomes in call order.

        A single call runs in the caller's thread (which must then outlive its child too).
        """
        outcomes: list[Outcome[T]] = [Outcome() for _ in calls]
        if len(calls) == 1:
            try:
                outcomes[0].value = calls[0]()
            except BaseException as exc:  # noqa: BLE001 - handed back to the caller
                outcomes[0].error = exc
        if len(calls) < 2:
            return outcomes
        left = [len(calls)]
        done = threading.Event()
        lock = threading.Lock()

        def task(index: int, call: Callable[[], T]) -> None:
            try:
                outcomes[index].value = call()
            except BaseException as exc:  # noqa: BLE001 - handed back to the caller
                outcomes[index].error = exc
            with lock:
                left[0] -= 1
                if not left[0]:
                    done.set()

        # the work first, then the threads: each one starts spawning as soon as it runs, so
        # the first node does not wait for a hundred thread start-ups (~7 ms of CPU), and
        # none is started once the queue is empty (those running took all the work)
        for index, call in enumerate(calls):
            self._work.put(functools.partial(task, index, call))
        while not self._work.empty() and len(self._threads) < min(self.max_threads, len(calls)):
            thread = threading.Thread(target=self._serve, daemon=True,
                                      name=f"{self._name} {len(self._threads)}")
            try:
                thread.start()
            except RuntimeError:   # no more threads allowed (RLIMIT_NPROC): use those we have
                break
            self._threads.append(thread)
        if not self._threads:
            self._drain()
        done.wait()
        return outcomes

    def _drain(self) -> None:
        """Run what is queued in this thread (no spawn thread could be started)."""
        while True:
            try:
                item = self._work.get_nowait()
            except queue.Empty:
                return
            if item is not None:
                item()

    def _serve(self) -> None:
        while True:
            item = self._work.get()
            if item is None:     # close()
                return
            item()

    def close(self) -> None:
        """End the threads; only once nothing they started can still be running.

        Not waited for (a hundred thread wake-ups at the end of every stop): they only
        return from an empty queue."""
        for _ in self._threads:
            self._work.put(None)
        self._threads.clear()
