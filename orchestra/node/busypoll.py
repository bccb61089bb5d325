"""Polling a connection briefly before blocking on it, when the answer is due within microseconds.

A thread that blocks in ``recv`` gives its CPU up; when the CPU has nothing else to run it
halts, and the answer's arrival then pays a cross-CPU wake-up (an interrupt to the halted
CPU, and in a virtual machine an exit to the hypervisor) before the thread runs again: on
the 2-core VM of docs/benchmarks.md that was ~40 of the ~100 µs of a kept-alive service call
between two pinned processes, for rospy as for us, while each side's own work (Python and
the two socket calls) is ~30 µs. Polling the socket for a bounded while instead keeps the
thread running, so the answer is read as soon as it lands; the kernel offers the same for
network cards (``SO_BUSY_POLL``), not for loopback.

The rule is adaptive and bounded, so a slow or rarely used peer costs nothing: a wait is
polled only when the previous wait on the same link ended within ``LIMIT_NS`` (the peer
answers fast), and never for longer than that; otherwise the thread blocks at once, as it
always did. The time of every wait is measured either way, so a peer that becomes fast is
polled again from the next call on. On a machine with one CPU nothing polls: the peer needs
that CPU to answer. The poll does not yield between its tries: on a busy CPU a yield hands
the CPU to another task for a whole time slice (ms; a yielding client ran at rospy's rate at
load 6, a spinning one at 2.6x it), and a peer on the same CPU, woken by our request,
preempts the poll anyway (31,000 calls/s with both on one CPU, rospy 7,000).
"""
from __future__ import annotations

import os
import socket
import time

#: longest poll of one wait (ns); a peer that answers later is waited for blocked
LIMIT_NS = 100_000
#: one turn of the poll loop (a recv that finds nothing) takes a few µs; a turn longer
#: than this means another task had the CPU
CONTENDED_NS = 30_000
#: after a poll that lost its CPU, this many waits block, doubling while it recurs (up to
#: BACKOFF_MAX) and halving after each STREAK polls in a row that kept their CPU
BACKOFF_MIN = 16
BACKOFF_MAX = 4096
STREAK = 64


def _multi_cpu() -> bool:
    """Whether the machine has more than one CPU (on a sole CPU polling only delays the
    peer that must answer). A process pinned to one CPU of several still polls: its peer
    is as likely elsewhere, and one on the same CPU preempts the poll when woken."""
    return (os.cpu_count() or 1) > 1


class BusyPoll:
    """Polling for one link (a service connection, a proxy's calls): whether to poll the
    next wait, and the poll itself.

    A poll that loses its CPU to another task (preempted: one turn took longer than
    ``CONTENDED_NS``) is worse than blocking: a thread that blocked is woken and preempts
    the running task when the answer lands, while a preempted one waits its turn, a time
    slice or more (ms). So a contended poll ends there, and the
    next waits block, ``BACKOFF_MIN`` of them at first, doubling while polls keep losing
    their CPU: on a busy machine this link behaves as if it never polled (one poll per
    ``BACKOFF_MAX`` waits, a lost slice of a few ms per ~4,096 calls). The backoff halves only
    after ``STREAK`` polls in a row kept their CPU, so the few lucky polls of a busy
    machine do not bring the costly ones back."""

    __slots__ = ("limit_ns", "last_ns", "skip", "backoff", "streak")

    def __init__(self, limit_ns: int = LIMIT_NS):
        self.limit_ns = limit_ns if _multi_cpu() else 0
        self.last_ns = 0  # how long the previous wait took; 0: none yet (poll)
        self.skip = 0  # waits left to block at once after a contended poll
        self.backoff = 0  # what ``skip`` was set to the last time
        self.streak = 0  # polls in a row that kept their CPU

    def budget(self) -> int:
        """How long to poll the next wait (ns); 0: block at once."""
        if self.skip:
            self.skip -= 1
            return 0
        return self.limit_ns if self.last_ns < self.limit_ns else 0

    def waited(self, start_ns: int) -> None:
        """Record that the wait begun at ``start_ns`` (``time.perf_counter_ns``) is over."""
        self.last_ns = time.perf_counter_ns() - start_ns

    def recv(self, sock: socket.socket, size: int, budget_ns: int) -> bytes | None:
        """Up to ``size`` bytes that arrive on ``sock`` within ``budget_ns``, without
        blocking; None when nothing came (b"" when the peer closed). ``sock`` must be in
        blocking mode (no timeout), as connections are once their headers are exchanged."""
        recv, flags, clock = sock.recv, socket.MSG_DONTWAIT, time.perf_counter_ns
        turn = clock()
        end = turn + budget_ns
        while True:
            try:
                data = recv(size, flags)
            except BlockingIOError:
                data = None
            last, turn = turn, clock()
            if turn - last > CONTENDED_NS:
                self.backoff = min(max(self.backoff * 2, BACKOFF_MIN), BACKOFF_MAX)
                self.skip, self.streak = self.backoff, 0
                return data
            if data is not None:
                self.streak += 1
                if self.streak >= STREAK:
                    self.backoff //= 2
                    self.streak = 0
                return data
            if turn >= end:
                return None
