"""A publisher's connection to one subscriber, driven over a socket pair (no master, no
processes): ``publish`` sends a small message itself when the writer thread is idle, and
whatever the socket does not take at once (a subscriber that stops reading, a big message)
follows through the writer thread; the subscriber must see every message, whole and in
order."""
from __future__ import annotations

import socket
import struct

import pytest

from orchestra.node import tcpros
from orchestra.node.msg import get_message_class
from orchestra.node.topics import OutConnection, Publication

pytestmark = pytest.mark.timeout(60)

STRING = get_message_class("std_msgs/String")


def _read_all(sock: socket.socket, count: int) -> list[bytes]:
    return [tcpros.read_message(sock) for _ in range(count)]


def test_messages_arrive_whole_and_in_order_when_the_socket_fills_midway():
    ours, theirs = socket.socketpair()
    ours.setsockopt(socket.SOL_SOCKET, socket.SO_SNDBUF, 4096)
    conn = OutConnection(Publication(None, "/t", STRING, False, None), ours, "/sub", None)
    conn.thread.start()
    sizes = [10, 3000, 5000, 10, OutConnection.DIRECT_MAX + 1, 7, 20000, 1] * 5
    sent = [struct.pack("<I", i) + bytes([i % 251]) * size for i, size in enumerate(sizes)]
    try:
        for data in sent:  # nobody reads yet: the socket fills and the queue takes the rest
            conn.enqueue(data)
        assert _read_all(theirs, len(sent)) == sent
        assert conn.messages_sent == len(sent)
        conn.enqueue(b"after")  # an idle connection again: sent by enqueue itself
        assert conn.idle() and tcpros.read_message(theirs) == b"after"
    finally:
        conn.close()
        theirs.close()


def test_a_small_message_on_an_idle_connection_is_sent_by_publish_itself():
    ours, theirs = socket.socketpair()
    conn = OutConnection(Publication(None, "/t", STRING, False, None), ours, "/sub", None)
    # writer thread not started: only a direct send can deliver
    try:
        conn.enqueue(b"now")
        assert conn.idle()
        assert tcpros.read_message(theirs) == b"now"
    finally:
        conn.close()
        theirs.close()


def test_a_subscriber_joins_before_it_can_read_our_header_so_no_message_falls_between():
    """The subscriber counts itself connected once it has our header (actionlib's
    wait_for_server does): a message published from then on must reach it, so the
    connection is in the publication before the header goes out, and the header first."""
    pub = Publication(None, "/t", STRING, False, None)
    ours, theirs = socket.socketpair()
    conn = pub.add_connection(ours, {"callerid": "/sub"},
                              tcpros.encode_header({"callerid": "/pub", "topic": "/t"}))
    try:
        assert conn in pub.connections
        pub.publish(STRING(data="first"))   # before the writer has sent the header, even
        assert tcpros.read_header(theirs) == {"callerid": "/pub", "topic": "/t"}
        assert tcpros.read_message(theirs) == STRING(data="first").serialize_bytes()
    finally:
        conn.close()
        theirs.close()
