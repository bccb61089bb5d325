"""XML-RPC plumbing shared by the master, node slave APIs, the launch server and the tools.

ROS 1 speaks XML-RPC everywhere: nodes register with the master, the master notifies nodes,
tools query both. The pieces every one of them needs (a threaded server that accepts any
request path, a client transport that gives up after a timeout, the default master address,
the errors that mean "nobody answered") are defined once here, at the bottom of the layer
picture, so master, node and supervise cannot drift apart (and need not import each other).
"""
from __future__ import annotations

import atexit
import logging
import os
import selectors
import socket
import socketserver
import struct
import threading
import xmlrpc.client
from collections.abc import Iterable, Mapping
from http.client import HTTPConnection, HTTPException
from typing import Any, cast
from urllib.parse import urlsplit, urlunsplit

from orchestra import xmlrpc_codec
from orchestra.errors import OrchestraError

log = logging.getLogger(__name__)

DEFAULT_PORT = 11311
DEFAULT_MASTER_URI = f"http://localhost:{DEFAULT_PORT}/"  # roscore's default

# what goes wrong on the wire when nobody (or something odd) answers
TRANSPORT_ERRORS: tuple[type[Exception], ...] = (
    OSError, HTTPException, xmlrpc.client.ProtocolError, xmlrpc.client.ResponseError)


class MasterUnreachable(OrchestraError):
    """No master answers at the given URI (a user-facing error: start one, or fix the URI)."""

    exit_code = 1


def master_uri_from_env(environ: Mapping[str, str] | None = None) -> str:
    """ROS_MASTER_URI, or roscore's default ``http://localhost:11311/``."""
    env = os.environ if environ is None else environ
    return env.get("ROS_MASTER_URI") or DEFAULT_MASTER_URI


# -- client side ------------------------------------------------------------------------------

class Transport(xmlrpc.client.Transport):
    """xmlrpc.client's HTTP transport (keep-alive, a retry on a reset kept connection),
    reading answers with ``xmlrpc_codec`` and giving up after ``timeout`` seconds.

    xmlrpc.client has no timeout of its own: a peer that accepts and never answers (a
    stopped node, a wedged master) would block the caller forever. Its answer reader feeds
    expat 1 KiB at a time through Python callbacks; a ROS answer is read whole instead.
    """

    def __init__(self, timeout: float | None = None):
        super().__init__()
        self.timeout = timeout

    def make_connection(self, host: Any) -> HTTPConnection:
        conn = super().make_connection(host)
        if self.timeout is not None:
            conn.timeout = self.timeout
        return conn

    def parse_response(self, response: Any) -> tuple[Any, ...]:
        body = response.read()
        if response.getheader("Content-Encoding", "") == "gzip":
            body = xmlrpc.client.gzip_decode(body)
        return xmlrpc_codec.loads(body)[0]


def proxy(uri: str, timeout: float | None = None) -> xmlrpc.client.ServerProxy:
    """An XML-RPC proxy for ``uri``; ``timeout`` bounds each call (None = wait forever).

    A proxy keeps one HTTP connection and is not thread-safe: make one per thread (on
    loopback a connect costs tens of microseconds).
    """
    return xmlrpc.client.ServerProxy(uri, transport=Transport(timeout))


def call(uri: str, method: str, *args: Any, timeout: float | None = None) -> Any:
    """``method(*args)`` at ``uri`` on a connection of its own, closed afterwards (a
    proxy otherwise holds its socket until it is garbage-collected)."""
    with proxy(uri, timeout) as server:
        return getattr(server, method)(*args)


class _Peer:
    """One kept connection to an XML-RPC server: a ``Transport`` and where to post."""

    def __init__(self, uri: str, timeout: float | None):
        where = urlsplit(uri)
        self.host = where.netloc
        self.handler = urlunsplit(("", "", *where[2:])) or "/RPC2"  # as ServerProxy does
        self.transport = Transport(timeout)

    def call(self, method: str, args: tuple[Any, ...]) -> Any:
        result = self.transport.request(self.host, self.handler,
                                        xmlrpc_codec.dumps_call(method, args))
        return result[0] if len(result) == 1 else result


class _ProxyPool:
    """Idle XML-RPC connections by (uri, timeout), lent out to one call at a time.

    A new connection per call costs ~0.6 ms on loopback (connect, and a server thread per
    connection), five times a call on an open keep-alive connection; rospy likewise keeps
    its proxies. Each connection is used by one thread at a time (an HTTP connection carries
    one call at a time); a stale kept-alive connection (peer restarted, idle timeout) is
    re-opened by xmlrpc.client's transport, which retries once on a reset. Calls are written
    and answers read by ``xmlrpc_codec``. A call that fails on the wire drops its connection.
    """

    MAX_IDLE = 8  # per (uri, timeout): more concurrent callers than that open their own

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._idle: dict[tuple[str, float | None], list[_Peer]] = {}

    def call(self, uri: str, method: str, *args: Any, timeout: float | None = None) -> Any:
        key = (uri, timeout)
        with self._lock:
            idle = self._idle.get(key)
            peer = idle.pop() if idle else None
        if peer is None:
            peer = _Peer(uri, timeout)
        try:
            result = peer.call(method, args)
        except xmlrpc.client.Fault:
            self._give_back(key, peer)
            raise
        except BaseException:
            peer.transport.close()
            raise
        self._give_back(key, peer)
        return result

    def _give_back(self, key: tuple[str, float | None], peer: _Peer) -> None:
        with self._lock:
            idle = self._idle.setdefault(key, [])
            if len(idle) < self.MAX_IDLE:
                idle.append(peer)
                return
        peer.transport.close()

    def close(self) -> None:
        """Close every idle connection (at exit, so none is left to the garbage collector)."""
        with self._lock:
            peers = [p for idle in self._idle.values() for p in idle]
            self._idle.clear()
        for peer in peers:
            peer.transport.close()


_POOL = _ProxyPool()
atexit.register(_POOL.close)


def pooled_call(uri: str, method: str, *args: Any, timeout: float | None = None) -> Any:
    """``method(*args)`` at ``uri`` over a kept connection (see ``_ProxyPool``): for callers
    that talk to the same peers again and again, as a node does with its master."""
    return _POOL.call(uri, method, *args, timeout=timeout)


def master_is_up(uri: str, timeout: float = 1.0) -> bool:
    """True when something at ``uri`` answers ``getPid`` like a ROS master.

    Here, not in master/, because the node tools ask it too and node/ sits below master/.
    """
    try:
        code, _, _ = unpack_reply(call(uri, "getPid", "/orchestra", timeout=timeout))
    except TRANSPORT_ERRORS:
        return False
    except (xmlrpc.client.Fault, ValueError, TypeError):  # something else answers there
        return False
    return code == 1


def unpack_reply(result: object) -> tuple[int, str, Any]:
    """A ROS XML-RPC answer ``[code, statusMessage, value]`` checked for its shape.

    Whatever a peer sends is untrusted: a reply of another shape raises ValueError (as
    unpacking it would) instead of surfacing later as an odd attribute error.
    """
    if not isinstance(result, (list, tuple)) or len(result) != 3:
        raise ValueError(f"malformed ROS XML-RPC reply {result!r:.200}")
    code, message, value = result
    if not isinstance(code, int):
        raise ValueError(f"malformed ROS XML-RPC status code {code!r:.50}")
    return code, str(message), value


def multicall_results(multi: xmlrpc.client.MultiCall) -> list[Any]:
    """Run ``multi`` and return every result (a Fault in any of them raises it).

    MultiCallIterator iterates through ``__getitem__``, which its type stubs do not model.
    """
    return list(cast(Iterable[Any], multi()))


# -- server side ------------------------------------------------------------------------------

_REASONS = {200: "OK", 400: "Bad Request", 408: "Request Timeout", 411: "Length Required",
            413: "Payload Too Large", 414: "URI Too Long", 431: "Request Header Fields Too Large",
            500: "Internal Server Error", 501: "Not Implemented"}
MAX_LINE = 65536          # a request line longer than this is refused (414)
MAX_HEAD = 65536          # and a request line plus headers longer than this (431)
MAX_HEADERS = 100
MAX_BODY = 64 * 2 ** 20   # a ROS call carries params, not bulk data
_STATUS_LINES = {(version, status): f"{version} {status} {reason}\r\n".encode()
                 for version in ("HTTP/1.0", "HTTP/1.1") for status, reason in _REASONS.items()}
_RECV = 65536             # bytes asked of one recv (a ROS call is far smaller)
_TIMEVAL = struct.Struct("@ll")  # SO_RCVTIMEO / SO_SNDTIMEO: struct timeval


def _os_timeouts(sock: socket.socket, seconds: float) -> None:
    """Bound each blocking recv and send of ``sock`` to ``seconds`` in the kernel.

    A Python-level timeout (``settimeout``) makes every recv and send a poll() first: two
    more system calls per request. SO_RCVTIMEO/SO_SNDTIMEO give the same bound on a
    blocking socket (a timed-out call raises OSError, as ``socket.timeout`` is one); where
    the platform refuses them, the Python timeout is used instead.
    """
    whole = int(seconds)
    timeval = _TIMEVAL.pack(whole, int((seconds - whole) * 1e6))
    try:
        sock.settimeout(None)
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVTIMEO, timeval)
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_SNDTIMEO, timeval)
    except (OSError, AttributeError):  # pragma: no cover - not Linux/BSD
        sock.settimeout(seconds)


def _head_end(buffer: bytes | bytearray, start: int = 0) -> tuple[int, int]:
    """(end of the request head, start of the body) in ``buffer``, looking from ``start``;
    (-1, -1) while the empty line that ends the head has not arrived. Lines end with CRLF,
    or LF alone (RFC 9112 lets a server accept that; this one always has)."""
    crlf = buffer.find(b"\n\r\n", start)
    lf = buffer.find(b"\n\n", start, crlf + 1 if crlf >= 0 else len(buffer))
    if lf >= 0:
        return lf, lf + 2
    if crlf >= 0:
        return crlf, crlf + 3
    return -1, -1


class AnyPathHandler(socketserver.BaseRequestHandler):
    """A lean HTTP/1.x handler for XML-RPC POSTs to any path (rospy and roscpp post to "/",
    others to "/RPC2").

    The stdlib's http.server parses every request's headers with the email package and does
    per-request bookkeeping that costs more than the XML-RPC call itself; a ROS call needs
    only the request line, Content-Length (and Content-Encoding, Connection). So the
    connection's own thread reads straight from the socket into one buffer (a ROS request
    usually arrives in one recv: head and body), finds the head's end with ``bytes.find``,
    answers with one ``sendall``, and reads the next request of a kept-alive connection:
    two system calls per request, no file objects, no thread hand-off. Bytes past one
    request (a pipelined next one) stay in the buffer for the next. The body goes to the
    server's dispatcher (``xmlrpc_codec``: the stdlib's reading and writing, faster for the
    documents ROS sends), whose faults are answered as XML-RPC faults, as SimpleXMLRPCServer
    does. ``protocol_version = "HTTP/1.1"`` keeps connections open between calls (rospy's
    and roscpp's clients reuse them); the default answers one call per connection.
    Oversized or malformed requests get their HTTP error and the connection is closed.
    """

    protocol_version = "HTTP/1.0"
    timeout: float | None = None  # seconds a connection may sit idle or take to send a call

    def setup(self) -> None:
        sock: socket.socket = self.request
        if self.timeout is not None:
            _os_timeouts(sock, self.timeout)
        try:  # one sendall per reply: nothing for Nagle to merge, so do not wait for ACKs
            sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        except OSError:  # pragma: no cover - not TCP
            pass
        self._buffer = b""

    def handle(self) -> None:
        try:
            while self._handle_one():
                pass
        except OSError:  # an idle connection timed out, or the peer went away
            pass

    def _handle_one(self) -> bool:
        """Answer one request; True when the connection stays open for another."""
        recv = self.request.recv
        buffer: bytes | bytearray = self._buffer
        scanned = 0
        while True:
            if buffer[:1] in (b"\r", b"\n"):  # tolerated between requests (RFC 9112, 2.2)
                buffer = buffer.lstrip(b"\r\n")
                scanned = 0
            head_end, body_start = _head_end(buffer, scanned)
            if head_end >= 0 or len(buffer) > MAX_HEAD:
                break
            scanned = max(0, len(buffer) - 2)  # the end marker may straddle two reads
            chunk = recv(_RECV)
            if not chunk:
                return False  # the peer closed (between requests, or giving up on one)
            if not buffer:
                buffer = chunk  # the usual case: the whole request in one read
            else:  # a head in pieces: grow in place, not by copying it each time
                if type(buffer) is bytes:
                    buffer = bytearray(buffer)
                buffer += chunk
        if not 0 <= head_end <= MAX_HEAD:  # the request line, or the whole head, too long
            return self._refuse(414 if buffer.find(b"\n", 0, MAX_LINE + 1) < 0 else 431)
        data = buffer if isinstance(buffer, bytes) else bytes(buffer)
        lines = data[:head_end].split(b"\n")
        parts = lines[0].split()
        if len(parts) != 3 or not parts[2].startswith(b"HTTP/"):
            return self._refuse(400)
        method, _, version = parts
        if len(lines) > MAX_HEADERS + 1:
            return self._refuse(431)
        headers: dict[bytes, bytes] = {}
        for header in lines[1:]:
            name, colon, value = header.partition(b":")
            if not colon:
                return self._refuse(400)
            headers[name.strip().lower()] = value.strip()
        if method != b"POST":
            return self._refuse(501)
        length = headers.get(b"content-length")
        if length is None:
            return self._refuse(411)
        if not length.isdigit():
            return self._refuse(400)
        size = int(length)
        if size > MAX_BODY:
            return self._refuse(413)
        body_end = body_start + size
        if len(data) >= body_end:
            body = data[body_start:body_end]
            self._buffer = data[body_end:]
        else:  # the rest of a large body: read exactly it, in chunks (no quadratic joins)
            chunks = [data[body_start:]]
            missing = body_end - len(data)
            while missing:
                chunk = recv(min(missing, 1 << 20))
                if not chunk:
                    return False
                chunks.append(chunk)
                missing -= len(chunk)
            body = b"".join(chunks)
            self._buffer = b""
        encoding = headers.get(b"content-encoding", b"identity").lower()
        keep = (self.protocol_version == "HTTP/1.1" and version == b"HTTP/1.1"
                and headers.get(b"connection", b"").lower() != b"close")
        try:
            if encoding == b"gzip":
                body = xmlrpc.client.gzip_decode(body)
            elif encoding != b"identity":
                return self._refuse(501)
            response = cast(Dispatcher, self.server).marshaled_dispatch(body)
        except Exception as exc:  # an undecodable body or a reply that cannot be encoded
            log.debug("XML-RPC request from %s refused: %s", self.client_address, exc)
            return self._refuse(500)
        self._send(200, response, b"text/xml", keep)
        return keep

    def _refuse(self, status: int) -> bool:
        """Answer ``status`` with an empty body and close the connection."""
        self._send(status, b"", b"text/plain", False)
        return False

    def _send(self, status: int, body: bytes, content_type: bytes, keep: bool) -> None:
        """The answer in one ``sendall`` (head and body: one segment for a small reply)."""
        self.request.sendall(
            b"%sContent-type: %s\r\nContent-length: %d\r\n%s\r\n%s"
            % (_STATUS_LINES[self.protocol_version, status], content_type, len(body),
               b"" if keep else b"Connection: close\r\n", body))


def _fault_text(exc: BaseException) -> str:
    """How an unexpected error is put in a fault (as SimpleXMLRPCDispatcher words it)."""
    return f"{type(exc)}:{exc}"


class Dispatcher:
    """XML-RPC method dispatch: registered functions, else one registered instance (its
    ``_dispatch(method, params)`` when it has one, else its public method of that name), and
    ``system.multicall``; a call's exception becomes an XML-RPC fault.

    The stdlib's SimpleXMLRPCDispatcher behaves the same, but importing xmlrpc.server pulls
    in http.server and pydoc (~5 ms of every node's start-up) for nothing used here.
    """

    def __init__(self, allow_none: bool = False):
        self.allow_none = allow_none
        self.funcs: dict[str, Any] = {}
        self.instance: Any = None

    def register_instance(self, instance: Any) -> None:
        self.instance = instance

    def register_function(self, function: Any, name: str | None = None) -> None:
        self.funcs[name or function.__name__] = function

    def register_multicall_functions(self) -> None:
        self.funcs["system.multicall"] = self.system_multicall

    def marshaled_dispatch(self, data: bytes) -> bytes:
        """The XML-RPC answer (a result or a fault) to the request body ``data``."""
        try:
            params, method = xmlrpc_codec.loads(data)
            result = self.dispatch(method or "", params)
            return xmlrpc_codec.dumps_response(result, self.allow_none)
        except xmlrpc.client.Fault as fault:
            return xmlrpc_codec.dumps_fault(fault, self.allow_none)
        except BaseException as exc:  # any error of a call is the caller's fault answer
            return xmlrpc_codec.dumps_fault(xmlrpc.client.Fault(1, _fault_text(exc)),
                                            self.allow_none)

    def dispatch(self, method: str, params: tuple[Any, ...]) -> Any:
        func = self.funcs.get(method)
        if func is None and self.instance is not None:
            own_dispatch = getattr(self.instance, "_dispatch", None)
            if own_dispatch is not None:
                return own_dispatch(method, params)
            if not method.startswith("_") and "." not in method:
                func = getattr(self.instance, method, None)
        if func is None:
            raise Exception(f'method "{method}" is not supported')
        return func(*params)

    def system_multicall(self, call_list: list[dict[str, Any]]) -> list[Any]:
        """Every call of ``call_list`` in turn: ``[result]`` or a fault struct each."""
        results: list[Any] = []
        for one in call_list:
            method, params = one["methodName"], one["params"]
            try:
                results.append([self.dispatch(method, params)])
            except xmlrpc.client.Fault as fault:
                results.append({"faultCode": fault.faultCode, "faultString": fault.faultString})
            except BaseException as exc:  # one failing call does not fail the others
                results.append({"faultCode": 1, "faultString": _fault_text(exc)})
        return results


class _XMLRPCServer(socketserver.TCPServer, Dispatcher):
    """TCP server + ``Dispatcher``, answering through the lean ``AnyPathHandler``."""

    allow_reuse_address = True

    def __init__(self, addr: tuple[str, int], handler: type[AnyPathHandler] = AnyPathHandler,
                 allow_none: bool = False, bind_and_activate: bool = True):
        Dispatcher.__init__(self, allow_none)
        socketserver.TCPServer.__init__(self, addr, handler, bind_and_activate)


class ThreadedServer(socketserver.ThreadingMixIn, _XMLRPCServer):
    """An XML-RPC server answering each connection in its own daemon thread.

    Threaded so that one slow call (a node's ``shutdown``, a master notifying a dead node)
    never blocks the others. IPv6 when the bind address is one.
    """

    daemon_threads = True
    allow_reuse_address = True

    def __init__(self, addr: tuple[str, int],
                 handler: type[AnyPathHandler] = AnyPathHandler,
                 allow_none: bool = False):
        self.address_family = socket.AF_INET6 if ":" in addr[0] else socket.AF_INET
        self._wake_r, self._wake_w = os.pipe()   # first: a failed bind calls server_close
        self._stop_asked = threading.Event()
        self._serving_done = threading.Event()
        self._serving_done.set()
        super().__init__(addr, handler=handler, allow_none=allow_none)

    @property
    def port(self) -> int:
        return int(self.server_address[1])

    def serve_forever(self, poll_interval: float | None = 0.5) -> None:
        """Serve until ``shutdown()``, which wakes this loop at once.

        socketserver's loop only notices a shutdown at its next poll, so every stop of a
        node (its slave API) or of a master waited up to ``poll_interval`` (0.2 s for a
        node): most of the time a Python node took to exit after SIGINT. ``None`` waits
        for a request or the shutdown only: this server has nothing to do between requests
        (``ThreadingMixIn`` reaps its threads as it starts new ones), and a node's slave
        thread waking 5 times a second took the GIL from the node's own threads for nothing.
        """
        self._serving_done.clear()
        try:
            with selectors.DefaultSelector() as selector:
                selector.register(self, selectors.EVENT_READ)
                selector.register(self._wake_r, selectors.EVENT_READ)
                while not self._stop_asked.is_set():
                    ready = [key.fileobj for key, _ in selector.select(poll_interval)]
                    if self._wake_r in ready:
                        os.read(self._wake_r, 64)
                    if self._stop_asked.is_set():
                        break
                    if self in ready:
                        self._handle_request_noblock()  # type: ignore[attr-defined]
                    self.service_actions()
        finally:
            self._stop_asked.clear()
            self._serving_done.set()

    def shutdown(self) -> None:
        """Stop ``serve_forever`` (now, not at its next poll) and wait until it returned."""
        self._stop_asked.set()
        if self._wake_w >= 0:    # (closed: nothing is serving)
            try:
                os.write(self._wake_w, b"x")
            except OSError:
                pass
        self._serving_done.wait()

    def server_close(self) -> None:
        super().server_close()
        for fd in (self._wake_r, self._wake_w):
            if fd >= 0:
                os.close(fd)
        self._wake_r = self._wake_w = -1    # never write to a number reused meanwhile


class PolledServer(_XMLRPCServer):
    """A single-threaded server driven by the caller's event loop: ``handle_ready`` answers
    one waiting request. A client gets ``client_timeout`` seconds to send it, so a slow or
    silent client cannot stall the loop."""

    def __init__(self, addr: tuple[str, int], allow_none: bool = False,
                 client_timeout: float = 2.0):
        super().__init__(addr, allow_none=allow_none)
        self.client_timeout = client_timeout
        self.timeout = 0  # handle_request never waits: the loop saw the socket readable
        self.socket.setblocking(False)

    @property
    def port(self) -> int:
        return int(self.server_address[1])

    def get_request(self) -> tuple[socket.socket, Any]:
        conn, addr = self.socket.accept()
        conn.settimeout(self.client_timeout)
        return conn, addr

    def handle_ready(self) -> None:
        """Answer the request the event loop found waiting on the listening socket."""
        self.handle_request()
