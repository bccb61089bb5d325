"""The XML-RPC server's HTTP layer (orchestra.rpc.AnyPathHandler) on raw sockets.

The handler reads requests straight from the socket into one buffer; these pin what a
client sees whatever way its bytes arrive (in pieces, pipelined, with blank lines or bare
LFs), the errors for malformed or oversized requests, and keep-alive vs. close.
"""
from __future__ import annotations

import gzip
import socket
import threading
import xmlrpc.client

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from orchestra import rpc


class _Handler(rpc.AnyPathHandler):
    protocol_version = "HTTP/1.1"
    timeout = 5


@pytest.fixture(scope="module")
def server():
    srv = rpc.ThreadedServer(("127.0.0.1", 0), handler=_Handler)
    srv.register_function(lambda x: [1, "echo", x], "echo")
    thread = threading.Thread(target=srv.serve_forever, daemon=True)
    thread.start()
    yield srv
    srv.shutdown()
    srv.server_close()


def _call(value: object) -> bytes:
    return xmlrpc.client.dumps((value,), "echo").encode()


def _request(body: bytes, *, eol: bytes = b"\r\n", extra: bytes = b"") -> bytes:
    return (b"POST / HTTP/1.1" + eol + b"Host: x" + eol + extra
            + b"Content-Length: " + str(len(body)).encode() + eol + eol + body)


def _read_answer(sock: socket.socket, buffer: bytes = b"") -> tuple[bytes, bytes, bytes]:
    """(head, body, bytes after them) of one HTTP answer."""
    while b"\r\n\r\n" not in buffer:
        chunk = sock.recv(65536)
        if not chunk:
            raise ConnectionError(f"closed after {buffer!r}")
        buffer += chunk
    head, _, rest = buffer.partition(b"\r\n\r\n")
    length = int(head.lower().split(b"content-length:")[1].split(b"\r\n")[0])
    while len(rest) < length:
        chunk = sock.recv(65536)
        if not chunk:
            raise ConnectionError("closed inside a body")
        rest += chunk
    return head, rest[:length], rest[length:]


def _connect(server) -> socket.socket:
    return socket.create_connection(server.server_address, timeout=5)


def _echoed(body: bytes) -> object:
    return xmlrpc.client.loads(body)[0][0][2]


def test_request_arriving_byte_by_byte_is_answered(server):
    with _connect(server) as sock:
        sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        for byte in _request(_call("slow")):
            sock.sendall(bytes([byte]))
        head, body, _ = _read_answer(sock)
    assert head.startswith(b"HTTP/1.1 200 OK") and _echoed(body) == "slow"


def test_pipelined_requests_in_one_send_are_answered_in_order(server):
    with _connect(server) as sock:
        sock.sendall(b"".join(_request(_call(i)) for i in range(5)))
        rest = b""
        for i in range(5):
            head, body, rest = _read_answer(sock, rest)
            assert b"Connection: close" not in head
            assert _echoed(body) == i


@given(st.lists(st.integers(1, 400), min_size=1, max_size=30),
       st.lists(st.sampled_from([b"\r\n", b"\n", b""]), min_size=3, max_size=3),
       st.sampled_from([b"\r\n", b"\n"]))
@settings(max_examples=60, deadline=None)
def test_any_split_of_a_request_stream_gets_the_same_answers(server, cuts, blanks, eol):
    stream = b"".join(blank + _request(_call(f"v{i}"), eol=eol) for i, blank in enumerate(blanks))
    with _connect(server) as sock:
        sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        at = 0
        for cut in cuts:
            if at < len(stream):
                sock.sendall(stream[at:at + cut])
                at += cut
        sock.sendall(stream[at:])
        rest = b""
        for i in range(3):
            head, body, rest = _read_answer(sock, rest)
            assert head.startswith(b"HTTP/1.1 200") and _echoed(body) == f"v{i}"


def test_gzip_body_is_read(server):
    with _connect(server) as sock:
        sock.sendall(_request(gzip.compress(_call("zipped")), extra=b"Content-Encoding: gzip\r\n"))
        _, body, _ = _read_answer(sock)
    assert _echoed(body) == "zipped"


def test_large_body_in_many_reads_is_read_whole(server):
    value = "x" * 3_000_000
    with _connect(server) as sock:
        sock.sendall(_request(_call(value)))
        _, body, _ = _read_answer(sock)
    assert _echoed(body) == value


def _answer_and_close(server, data: bytes) -> tuple[bytes, bytes]:
    with _connect(server) as sock:
        sock.sendall(data)
        head, body, rest = _read_answer(sock)
        assert rest == b"" and sock.recv(10) == b""  # closed after the answer
    return head, body


@pytest.mark.parametrize("data, status", [
    (b"GET / HTTP/1.1\r\nHost: x\r\n\r\n", b"501"),
    (b"POST / HTTP/1.1\r\nHost: x\r\n\r\n", b"411"),
    (b"POST / HTTP/1.1\r\nContent-Length: 1x\r\n\r\n", b"400"),
    (b"POST / HTTP/1.1\r\nContent-Length: 99999999999\r\n\r\n", b"413"),
    (b"POST /\r\nContent-Length: 0\r\n\r\n", b"400"),
    (b"POST / FTP/1.1\r\nContent-Length: 0\r\n\r\n", b"400"),
    (b"POST / HTTP/1.1\r\nno colon here\r\n\r\n", b"400"),
    (b"POST / HTTP/1.1\r\nContent-Encoding: br\r\nContent-Length: 0\r\n\r\n", b"501"),
    (b"POST / HTTP/1.1\r\n" + b"A: b\r\n" * (rpc.MAX_HEADERS + 1) + b"Content-Length: 0\r\n\r\n",
     b"431"),
    (b"POST /" + b"a" * (rpc.MAX_LINE + 10) + b" HTTP/1.1\r\n\r\n", b"414"),
    (b"POST / HTTP/1.1\r\nA: " + b"b" * (rpc.MAX_HEAD + 10) + b"\r\n\r\n", b"431"),
])
def test_malformed_or_oversized_requests_get_their_status_and_are_closed(server, data, status):
    head, body = _answer_and_close(server, data)
    assert head.split()[1] == status and body == b""


def test_head_that_never_ends_is_refused_once_past_the_limit(server):
    with _connect(server) as sock:
        sock.sendall(b"POST / HTTP/1.1\r\n")
        for _ in range(rpc.MAX_HEAD // 4096 + 2):
            sock.sendall(b"X-Filler: " + b"f" * 4080 + b"\r\n")
        head, _, _ = _read_answer(sock)
    assert head.split()[1] == b"431"


def test_connection_close_and_http10_requests_are_answered_then_closed(server):
    for data in (_request(_call(1), extra=b"Connection: close\r\n"),
                 _request(_call(2)).replace(b"HTTP/1.1", b"HTTP/1.0", 1)):
        head, _ = _answer_and_close(server, data)
        assert head.startswith(b"HTTP/1.1 200") and b"Connection: close" in head


def test_http10_server_closes_after_each_answer():
    srv = rpc.ThreadedServer(("127.0.0.1", 0))
    srv.register_function(lambda x: x, "echo")
    threading.Thread(target=srv.serve_forever, daemon=True).start()
    try:
        head, _ = _answer_and_close(srv, _request(_call(3)))
        assert head.startswith(b"HTTP/1.0 200 OK") and b"Connection: close" in head
    finally:
        srv.shutdown()
        srv.server_close()


def test_idle_kept_connection_is_closed_after_the_timeout():
    class Quick(rpc.AnyPathHandler):
        protocol_version = "HTTP/1.1"
        timeout = 0.2

    srv = rpc.ThreadedServer(("127.0.0.1", 0), handler=Quick)
    threading.Thread(target=srv.serve_forever, daemon=True).start()
    try:
        with _connect(srv) as sock:
            sock.sendall(b"POST / HTTP/1.1\r\n")  # and nothing more
            assert sock.recv(10) == b""  # the server gave up on it (recv waits up to 5 s)
    finally:
        srv.shutdown()
        srv.server_close()
