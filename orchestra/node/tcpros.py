"""TCPROS framing: connection headers and length-prefixed messages over a TCP socket.

A connection header is ``uint32 total`` then repeated ``uint32 len`` + ``key=value``; every
message after it is ``uint32 len`` + body; a service response is prefixed by one "ok" byte
(1 = response follows, 0 = an error string follows). All integers little-endian. These are
the bytes rospy and roscpp speak, so orchestra nodes and real ROS nodes interoperate.
"""
from __future__ import annotations

import socket
import struct

from orchestra.node.exceptions import TransportException

_U32 = struct.Struct("<I")
MAX_HEADER = 1 << 20     # a header bigger than this is garbage, not a header
MAX_MESSAGE = 1 << 30


def encode_header(fields: dict[str, str]) -> bytes:
    """The wire form of a connection header (values are str; utf-8 on the wire)."""
    body = bytearray()
    for key, value in fields.items():
        item = f"{key}={value}".encode()
        body += _U32.pack(len(item))
        body += item
    return _U32.pack(len(body)) + bytes(body)


def decode_header(data: bytes) -> dict[str, str]:
    """Parse a header body (without its leading total length)."""
    fields: dict[str, str] = {}
    pos = 0
    while pos < len(data):
        if pos + 4 > len(data):
            raise TransportException("truncated connection header")
        (size,) = _U32.unpack_from(data, pos)
        pos += 4
        if pos + size > len(data):
            raise TransportException("connection header field runs past the header")
        item = data[pos:pos + size].decode("utf-8", "replace")
        pos += size
        key, sep, value = item.partition("=")
        if not sep:
            raise TransportException(f"connection header field without '=': {item!r}")
        fields[key] = value
    return fields


def recv_exact(sock: socket.socket, size: int) -> bytes:
    """Exactly ``size`` bytes, or ``TransportException`` when the peer closes first."""
    if size == 0:
        return b""
    buf = bytearray(size)
    view = memoryview(buf)
    got = 0
    while got < size:
        n = sock.recv_into(view[got:], size - got)
        if n == 0:
            raise TransportException("connection closed by peer")
        got += n
    return bytes(buf)


def read_header(sock: socket.socket) -> dict[str, str]:
    (size,) = _U32.unpack(recv_exact(sock, 4))
    if size > MAX_HEADER:
        raise TransportException(f"connection header of {size} bytes refused")
    return decode_header(recv_exact(sock, size))


def write_header(sock: socket.socket, fields: dict[str, str]) -> None:
    sock.sendall(encode_header(fields))


def read_message(sock: socket.socket) -> bytes:
    (size,) = _U32.unpack(recv_exact(sock, 4))
    if size > MAX_MESSAGE:
        raise TransportException(f"message of {size} bytes refused")
    return recv_exact(sock, size)


def frame(body: bytes | bytearray) -> list[bytes | bytearray]:
    """Length prefix + body as separate buffers (sent with ``sendmsg``, no copy of body)."""
    return [_U32.pack(len(body)), body]


def send_message(sock: socket.socket, body: bytes | bytearray) -> None:
    send_buffers(sock, frame(body))


def send_buffers(sock: socket.socket, buffers: list) -> None:
    """Send every buffer completely (sendmsg may write only part of them)."""
    total = sum(len(b) for b in buffers)
    sent = sock.sendmsg(buffers)
    if sent == total:
        return
    data = b"".join(bytes(b) for b in buffers)
    sock.sendall(data[sent:])


def read_service_response(sock: socket.socket) -> tuple[bool, bytes]:
    """(ok, body) of one service reply: body is the response, or the error text."""
    ok = recv_exact(sock, 1)
    return ok == b"\x01", read_message(sock)


def send_service_response(sock: socket.socket, ok: bool, body: bytes | bytearray) -> None:
    send_buffers(sock, [b"\x01" if ok else b"\x00", _U32.pack(len(body)), body])


def parse_rosrpc_uri(uri: str) -> tuple[str, int]:
    """``rosrpc://host:port`` -> (host, port)."""
    if not uri.startswith("rosrpc://"):
        raise TransportException(f"not a rosrpc URI: {uri!r}")
    rest = uri[len("rosrpc://"):].rstrip("/")
    host, _, port = rest.rpartition(":")
    try:
        return host, int(port)
    except ValueError:
        raise TransportException(f"bad port in service URI {uri!r}") from None


def connect(host: str, port: int, timeout: float | None = 5.0) -> socket.socket:
    """A connected TCP socket with Nagle off (latency matters more than packet count here)."""
    sock = socket.create_connection((host, port), timeout=timeout)
    sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
    sock.settimeout(None)
    return sock
