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


def test_poll_recv_returns_what_arrives_while_it_polls():
    a, b = socket.socketpair()
    with a, b:
        sender = threading.Timer(0.01, a.sendall, args=(b"reply",))
        sender.start()
        got = busypoll.poll_recv(b, 100, 10 * 1_000_000_000)  # ends when the reply lands
        sender.join()
        assert got == b"reply"


def test_poll_recv_gives_up_when_nothing_comes_and_reports_a_closed_peer():
    a, b = socket.socketpair()
    with b:
        assert busypoll.poll_recv(b, 100, 1_000_000) is None
        assert b.getblocking()  # still a blocking socket for the read that follows
        a.close()
        assert busypoll.poll_recv(b, 100, 1_000_000) == b""


def test_reader_poll_keeps_what_it_read_for_the_framed_reads_after_it():
    a, b = socket.socketpair()
    with a, b:
        reader = tcpros.Reader(b)
        reader.poll(1_000_000)  # nothing there: nothing buffered, nothing lost
        tcpros.send_service_response(a, True, b"one")
        tcpros.send_service_response(a, False, b"two")
        reader.poll(10 * 1_000_000_000)
        assert reader.service_response() == (True, b"one")
        reader.poll(10 * 1_000_000_000)  # the rest is buffered already: no recv
        assert reader.service_response() == (False, b"two")
        a.sendall(struct.pack("<I", 3) + b"abc")
        reader.poll(0)  # no budget: the read below blocks as before
        assert reader.message() == b"abc"
