"""Polling a service connection before blocking: when it polls, what it reads, when it gives up."""
from __future__ import annotations

import socket
import struct
import threading
import time

from orchestra.node import busypoll, tcpros
from orchestra.node.busypoll import BusyPoll


def test_first_wait_is_polled_then_only_while_the_peer_answers_within_the_limit():
    poll = BusyPoll(limit_ns=1_000_000)
    assert poll.budget() == 1_000_000  # nothing known yet: poll
    poll.waited(time.perf_counter_ns() - 5_000_000)  # that wait took 5 ms
    assert poll.budget() == 0  # a slow peer: block at once
    poll.waited(time.perf_counter_ns())  # the peer became fast again
    assert poll.budget() == 1_000_000


def test_a_machine_with_one_cpu_never_polls(monkeypatch):
    monkeypatch.setattr(busypoll.os, "cpu_count", lambda: 1)
    assert BusyPoll().budget() == 0


def test_recv_returns_what_arrives_while_it_polls(monkeypatch):
    # every turn of the poll looks short (the sending thread here takes the GIL, which a
    # real poll counts as losing its CPU)
    clock = iter(range(1 << 60))
    monkeypatch.setattr(busypoll.time, "perf_counter_ns", lambda: next(clock))
    a, b = socket.socketpair()
    with a, b:
        sender = threading.Timer(0.01, a.sendall, args=(b"reply",))
        sender.start()
        got = BusyPoll().recv(b, 100, 1 << 50)  # ends when the reply lands
        sender.join()
        assert got == b"reply"


def test_recv_gives_up_when_nothing_comes_and_reports_a_closed_peer():
    a, b = socket.socketpair()
    with b:
        assert BusyPoll().recv(b, 100, 1_000_000) is None
        assert b.getblocking()  # still a blocking socket for the read that follows
        a.close()
        assert BusyPoll().recv(b, 100, 1_000_000) == b""


def test_a_poll_that_loses_its_cpu_makes_the_next_waits_block_longer_each_time(monkeypatch):
    a, b = socket.socketpair()
    clock = iter(range(0, 1 << 60, busypoll.CONTENDED_NS + 1))  # every turn looks preempted
    monkeypatch.setattr(busypoll.time, "perf_counter_ns", lambda: next(clock))
    with a, b:
        poll = BusyPoll(limit_ns=1 << 50)
        assert poll.recv(b, 100, poll.budget()) is None
        assert [poll.budget() for _ in range(busypoll.BACKOFF_MIN)] == [0] * busypoll.BACKOFF_MIN
        assert poll.budget() > 0  # then it tries again
        poll.recv(b, 100, 1 << 50)  # and loses its CPU again: twice as long
        assert [poll.budget() for _ in range(2 * busypoll.BACKOFF_MIN)] == [0] * (
            2 * busypoll.BACKOFF_MIN)
        assert poll.budget() > 0


def test_reader_poll_keeps_what_it_read_for_the_framed_reads_after_it():
    a, b = socket.socketpair()
    with a, b:
        reader = tcpros.Reader(b)
        reader.poll(BusyPoll(limit_ns=1_000_000))  # nothing there: nothing buffered or lost
        tcpros.send_service_response(a, True, b"one")
        tcpros.send_service_response(a, False, b"two")
        reader.poll(BusyPoll(limit_ns=10 * 1_000_000_000))
        assert reader.service_response() == (True, b"one")
        reader.poll(BusyPoll(limit_ns=10 * 1_000_000_000))  # the rest is buffered: no recv
        assert reader.service_response() == (False, b"two")
        a.sendall(struct.pack("<I", 3) + b"abc")
        reader.poll(BusyPoll(limit_ns=0))  # no budget: the read below blocks as before
        assert reader.message() == b"abc"


def test_the_backoff_halves_only_after_a_streak_of_polls_that_kept_their_cpu(monkeypatch):
    a, b = socket.socketpair()
    ticks = iter(range(0, 1 << 60, busypoll.CONTENDED_NS + 1))
    monkeypatch.setattr(busypoll.time, "perf_counter_ns", lambda: next(ticks))
    with a, b:
        poll = BusyPoll(limit_ns=1 << 50)
        poll.recv(b, 100, 1 << 50)  # contended: BACKOFF_MIN waits block
        poll.recv(b, 100, 1 << 50)  # again: twice that
        assert poll.backoff == 2 * busypoll.BACKOFF_MIN
        quick = iter(range(1 << 60))
        monkeypatch.setattr(busypoll.time, "perf_counter_ns", lambda: next(quick))
        for _ in range(busypoll.STREAK - 1):
            a.sendall(b"x")
            assert poll.recv(b, 100, 1 << 50) == b"x"
        assert poll.backoff == 2 * busypoll.BACKOFF_MIN  # one lucky poll changes nothing
        a.sendall(b"x")
        poll.recv(b, 100, 1 << 50)
        assert poll.backoff == busypoll.BACKOFF_MIN
