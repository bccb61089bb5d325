"""TCPROS framing: connection headers and length-prefixed messages over a TCP socket.

A connection header is ``uint32 total`` then repeated ``uint32 len`` + ``key=value``; every
message after it is ``uint32 len`` + body; a service response is prefixed by one "ok" byte
(1 = response follows, 0 = an error string follows). All integers little-endian. These are
the bytes rospy and roscpp speak, so orchestra nodes and real ROS nodes interoperate.
"""
from __future__ import annotations

import socket
import struct

from orchestra.node import busypoll
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
    _recv_into_full(sock, memoryview(buf))
    return bytes(buf)


def _recv_into_full(sock: socket.socket, view: memoryview) -> None:
    got, size = 0, len(view)
    while got < size:
        n = sock.recv_into(view[got:], size - got)
        if n == 0:
            raise TransportException("connection closed by peer")
        got += n


def _header_size(raw: bytes) -> int:
    (size,) = _U32.unpack(raw)
    if size > MAX_HEADER:
        raise TransportException(f"connection header of {size} bytes refused")
    return size


def _message_size(raw: bytes) -> int:
    (size,) = _U32.unpack(raw)
    if size > MAX_MESSAGE:
        raise TransportException(f"message of {size} bytes refused")
    return size


class _Framing:
    """The TCPROS read rules over some way of getting the next n bytes (``exact``)."""

    def exact(self, size: int) -> bytes:
        raise NotImplementedError

    def header(self) -> dict[str, str]:
        return decode_header(self.exact(_header_size(self.exact(4))))

    def message(self) -> bytes:
        return self.exact(_message_size(self.exact(4)))

    def service_response(self) -> tuple[bool, bytes]:
        """(ok, body) of one service reply: body is the response, or the error text."""
        ok = self.exact(1)
        return ok == b"\x01", self.message()


class ExactReader(_Framing):
    """Reads exactly what is asked and not a byte more: a publisher may send messages
    right behind its header, and whoever reads the socket next must get them."""

    def __init__(self, sock: socket.socket):
        self.sock = sock

    def exact(self, size: int) -> bytes:
        return recv_exact(self.sock, size)


def read_header(sock: socket.socket) -> dict[str, str]:
    return ExactReader(sock).header()


def write_header(sock: socket.socket, fields: dict[str, str]) -> None:
    sock.sendall(encode_header(fields))


def refuse(sock: socket.socket, error: str) -> None:
    """Answer a connection with an ``error`` header and close it (the peer may be gone
    already: nothing to tell it then)."""
    try:
        write_header(sock, {"error": error})
    except OSError:
        pass
    finally:
        sock.close()


def read_message(sock: socket.socket) -> bytes:
    return ExactReader(sock).message()


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
    return ExactReader(sock).service_response()


class Reader(_Framing):
    """Reads one connection through a buffer: a single ``recv`` usually brings a whole
    header, request or reply (ok byte, length and body together), where reading each part
    exactly costs a system call apiece. For connections whose every byte is read here
    (service calls, both ends); a topic subscriber reads its publisher's header with
    ``read_header`` instead, then the stream in its own loop."""

    CHUNK = 65536

    def __init__(self, sock: socket.socket):
        self.sock = sock
        self._data = b""
        self._pos = 0

    def poll(self, busy: busypoll.BusyPoll) -> None:
        """When nothing is buffered and ``busy`` says so, poll the socket for what comes
        next (an answer due within microseconds is read without the thread sleeping);
        what arrives is buffered for ``exact``."""
        if self._pos < len(self._data):
            return
        budget = busy.budget()
        if budget <= 0:
            return
        chunk = busy.recv(self.sock, self.CHUNK, budget)
        if chunk:  # (b"": the peer closed; the next read finds that out again)
            self._data, self._pos = chunk, 0

    def exact(self, size: int) -> bytes:
        """The next ``size`` bytes; ``TransportException`` when the peer closes first."""
        data, pos = self._data, self._pos
        end = pos + size
        if end <= len(data):
            self._pos = end
            return data[pos:end]
        have = data[pos:]
        self._data, self._pos = b"", 0
        if size - len(have) >= self.CHUNK:  # a big body: straight into its own buffer
            buf = bytearray(size)
            buf[:len(have)] = have
            _recv_into_full(self.sock, memoryview(buf)[len(have):])
            return bytes(buf)
        while len(have) < size:
            chunk = self.sock.recv(self.CHUNK)
            if not chunk:
                raise TransportException("connection closed by peer")
            have += chunk
        self._data, self._pos = have, size
        return have[:size]


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
