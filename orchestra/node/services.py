"""Services over TCPROS: ``Service`` (serve a handler) and ``ServiceProxy`` (call one).

Wire rules (ROS 1): the client sends a header with ``service``, ``md5sum``, ``callerid`` and
optionally ``persistent=1`` or ``probe=1``; the server answers with its header (or an
``error`` header and closes). Each request is length-prefixed; each reply is an ok byte
(1/0) then a length-prefixed response or error string. A non-persistent connection carries
one call; a persistent one carries calls until the client closes it.
"""
from __future__ import annotations

import functools
import logging
import os
import socket
import sys
import threading
import time
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from orchestra.node import context, names, tcpros
from orchestra.node.busypoll import BusyPoll
from orchestra.node.exceptions import (
    ROSException,
    ROSInterruptException,
    ServiceException,
    TransportException,
)
from orchestra.node.masterapi import Master, MasterError
from orchestra.node.msg import Message, ServiceDefinition
from orchestra.rpc import master_uri_from_env

if TYPE_CHECKING:
    from orchestra.node.runtime import NodeRuntime

log = logging.getLogger(__name__)


def _as_response(value: Any, response_class: type[Message]) -> Message:
    """What a handler returned, as a response message (rospy accepts these shapes too).

    ``None`` is no answer, as in rospy: a handler that cannot process a request may return
    it, and the caller gets an error rather than a response that looks like a success."""
    if isinstance(value, response_class):
        return value
    if value is None:
        raise ServiceException("service handler returned None")
    if isinstance(value, Message):
        raise ServiceException(f"handler returned a {value._type}, expected "
                               f"{response_class._type}")
    if isinstance(value, dict):
        return response_class(**value)
    if isinstance(value, (list, tuple)):
        return response_class(*value)
    if len(response_class._fields) == 1:
        return response_class(value)
    raise ServiceException(f"handler returned {value!r}, expected {response_class._type}")


class ServiceServer:
    """One service this node offers (shared by the ``Service`` handle that created it)."""

    def __init__(self, runtime: NodeRuntime, name: str, srv_class: type[ServiceDefinition],
                 handler: Callable):
        self.runtime = runtime
        self.name = name
        self.srv_class = srv_class
        self.handler = handler
        self.calls = 0
        self.bytes_in = 0
        self.bytes_out = 0
        self.closed = False
        self.sockets: set[socket.socket] = set()
        self.lock = threading.Lock()

    def header(self) -> dict[str, str]:
        cls = self.srv_class
        return {"callerid": self.runtime.name, "service": self.name, "md5sum": cls._md5sum,
                "type": cls._type, "request_type": cls._request_class._type,
                "response_type": cls._response_class._type}

    def handle(self, sock: socket.socket, reader: tcpros.Reader, header: dict[str, str]) -> None:
        """Serve one client connection (runs on the connection's own thread); ``reader``
        holds whatever the client sent after its header."""
        caller = header.get("callerid", "?")
        cls = self.srv_class
        if header.get("probe") == "1":
            try:
                tcpros.write_header(sock, self.header())
            finally:
                sock.close()
            return
        their = header.get("md5sum", "")
        if their not in ("*", cls._md5sum):
            log.warning("refused call of %s by %s: it expects md5 %s, the service is %s (%s)",
                        self.name, caller, their, cls._type, cls._md5sum)
            tcpros.refuse(sock, f"request from [{caller}]: md5sums do not match: [{their}] vs. "
                                f"[{cls._md5sum}]")
            return
        persistent = header.get("persistent") == "1"
        # a kept connection's next request often follows the reply within microseconds
        poll = BusyPoll() if persistent else None
        with self.lock:
            self.sockets.add(sock)
        try:
            tcpros.write_header(sock, self.header())
            while not self.closed:
                try:
                    if poll is None:
                        data = reader.message()
                    else:
                        start = time.perf_counter_ns()
                        reader.poll(poll)
                        data = reader.message()
                        poll.waited(start)
                except TransportException:
                    return
                self._answer(sock, data, caller)
                if not persistent:
                    return
        except OSError as exc:
            log.debug("service %s: connection from %s broke: %s", self.name, caller, exc)
        finally:
            with self.lock:
                self.sockets.discard(sock)
            sock.close()

    def _answer(self, sock: socket.socket, data: bytes, caller: str) -> None:
        cls = self.srv_class
        try:
            request = cls._request_class.deserialize_bytes(data)
            response = _as_response(self.handler(request), cls._response_class)
            body = response.serialize_bytes()
        except ServiceException as exc:  # no (usable) response: rospy's words for it
            log.error("service %s: cannot process request from %s: %s", self.name, caller, exc)
            tcpros.send_service_response(sock, False,
                                         f"service cannot process request: {exc}".encode())
            return
        except Exception as exc:  # the handler's error goes back to the caller
            log.error("service %s: error processing request from %s: %s", self.name, caller, exc)
            tcpros.send_service_response(sock, False,
                                         f"error processing request: {exc}".encode())
            return
        self.calls += 1
        self.bytes_in += len(data) + 4
        self.bytes_out += len(body) + 5
        tcpros.send_service_response(sock, True, body)

    def close(self) -> None:
        self.closed = True
        with self.lock:
            socks = list(self.sockets)
        for sock in socks:
            try:
                sock.shutdown(socket.SHUT_RDWR)
            except OSError:
                pass


class Service:
    """Offer ``name`` (resolved like rospy): ``handler(request)`` returns the response."""

    def __init__(self, name: str, service_class: type[ServiceDefinition], handler: Callable,
                 **_ignored: Any):
        self._rt = context.current()
        self.resolved_name = self.name = self._rt.resolve_name(name)
        self.service_class = service_class
        self.handler = handler
        self._impl = self._rt.add_service(ServiceServer(self._rt, self.name, service_class,
                                                        handler))

    def shutdown(self, reason: str = "") -> None:
        self._rt.remove_service(self._impl)

    unregister = shutdown

    def spin(self) -> None:
        self._rt.spin()


class _Connection:
    """A client's connection to a service at ``uri``: the socket, its reader and, once the
    server has answered our header, the server's header."""

    def __init__(self, uri: str, sock: socket.socket):
        self.uri = uri
        self.sock = sock
        self.reader = tcpros.Reader(sock)
        self.header: dict[str, str] = {}

    def greeted(self, name: str) -> _Connection:
        """Read the server's header (ours went out on connecting); a refusal (an ``error``
        header) is a ``ServiceException``; a broken connection raises as it comes."""
        header = self.reader.header()
        if "error" in header:
            self.close()
            raise ServiceException(f"service [{name}] refused the connection: {header['error']}")
        self.header = header
        return self

    def call(self, body: bytes | bytearray, poll: BusyPoll) -> tuple[bool, bytes]:
        """Send one request, read its reply (polled for first when ``poll`` says the
        service answers fast)."""
        tcpros.send_message(self.sock, body)
        start = time.perf_counter_ns()
        self.reader.poll(poll)
        reply = self.reader.service_response()
        poll.waited(start)
        return reply

    def close(self) -> None:
        self.sock.close()


def _is_local(uri: str) -> bool:
    """Whether a ``rosrpc://`` URI names this machine (loopback or our host name)."""
    host = tcpros.parse_rosrpc_uri(uri)[0]
    return host == "localhost" or host.startswith("127.") or host in ("::1", _hostname())


@functools.cache
def _hostname() -> str:
    return socket.gethostname()


def _lookup(master, name: str) -> str:
    try:
        return master.call("lookupService", name)
    except MasterError as exc:
        raise ServiceException(f"service [{name}] unavailable") from exc


def _dial(uri: str, name: str, hello: bytes, timeout: float | None = 10.0) -> _Connection:
    """Connect to the service at ``uri`` and send our header ``hello``."""
    host, port = tcpros.parse_rosrpc_uri(uri)
    try:
        sock = tcpros.connect(host, port, timeout=timeout)
    except OSError as exc:
        raise ServiceException(f"unable to connect to service [{name}] at {uri}: {exc}") from exc
    try:
        sock.sendall(hello)
    except OSError as exc:
        sock.close()
        raise ServiceException(f"service [{name}]: connection failed: {exc}") from exc
    return _Connection(uri, sock)


def _greet(conn: _Connection, name: str) -> _Connection:
    try:
        return conn.greeted(name)
    except (OSError, TransportException) as exc:
        conn.close()
        raise ServiceException(f"service [{name}]: connection failed: {exc}") from exc


def _open(master, name: str, hello: bytes, last_uri: str | None) -> _Connection:
    """Look ``name`` up (every call, as rospy does: the service may have moved) and
    connect to it, headers exchanged.

    The master's answer is a round trip of its own, as long as connecting and exchanging
    headers; so when the service was found at ``last_uri`` before, on this machine, that
    connection is opened and greeted first and the server answers our header while the
    master answers the lookup. Used when the master names the same place; closed unused
    otherwise (the service moved or is gone: the result is then exactly that of looking up
    first). Only on this machine, where a connect is answered at once (accepted or
    refused): a remote host that went away would hold the call up until the connect gave
    up, even when the master knows the service is elsewhere now."""
    early = None
    if last_uri is not None and _is_local(last_uri):
        try:
            early = _dial(last_uri, name, hello)
        except (ServiceException, TransportException):
            early = None  # not there any more: the lookup decides
    try:
        uri = _lookup(master, name)
    except BaseException:
        if early is not None:
            early.close()
        raise
    if early is not None:
        if early.uri == uri:
            try:
                return early.greeted(name)
            except (OSError, TransportException):
                pass  # broke while we looked it up: a fresh connection decides
        early.close()
    return _greet(_dial(uri, name, hello), name)


class NoNode:
    """What a service client works with when the process is not a node (yet): rospy lets a
    script call services without ``init_node`` (the tutorials' add_two_ints_client does).
    The caller id is rospy's ``/unnamed``; names resolve in ``__ns:=``/ROS_NAMESPACE with
    the command line's remappings (rospy ignores them until ``init_node``: docs/compat.md);
    the master is ``__master:=``/ROS_MASTER_URI's."""

    def __init__(self, argv: list[str] | None = None):
        parsed = names.parse_args(list(sys.argv if argv is None else argv))
        special = parsed.special
        self.name = "/unnamed"
        self.namespace = names.make_global_ns(special.get("__ns")
                                              or os.environ.get("ROS_NAMESPACE") or "/")
        self.remaps = names.resolve_remaps(parsed.remaps, self.namespace, self.name)
        self.master = Master(special.get("__master") or master_uri_from_env(), self.name)

    def resolve_name(self, name: str) -> str:
        if not names.is_legal_name(name):
            raise ValueError(f"illegal ROS name: {name!r}")
        return names.resolve(name, self.namespace, self.name, self.remaps)

    def is_shutdown(self) -> bool:
        return False


def client_context() -> NodeRuntime | NoNode:
    """This process's node, or a ``NoNode`` before ``init_node``."""
    return context.current_or_none() or NoNode()


class ServiceProxy:
    """Call a service: ``proxy(request)`` or ``proxy(**fields)`` returns the response."""

    def __init__(self, name: str, service_class: type[ServiceDefinition],
                 persistent: bool = False, headers: dict | None = None):
        # as in rospy, a script need not be a node to call a service
        self._rt = client_context()
        self.resolved_name = self.name = self._rt.resolve_name(name)
        self.service_class = service_class
        self.request_class = service_class._request_class
        self.response_class = service_class._response_class
        self.persistent = persistent
        fields = {"callerid": self._rt.name, "service": self.name,
                  "md5sum": service_class._md5sum, "type": service_class._type}
        if persistent:
            fields["persistent"] = "1"
        self._hello = tcpros.encode_header(fields)
        self._conn: _Connection | None = None
        self._last_uri: str | None = None  # where the service was found last
        self._poll = BusyPoll()  # how fast the service answered last
        self._lock = threading.Lock()

    def wait_for_service(self, timeout: float | None = None) -> None:
        wait_for_service(self.name, timeout)

    def __call__(self, *args, **kwargs) -> Message:
        return self.call(*args, **kwargs)

    def call(self, *args, **kwargs) -> Message:
        if len(args) == 1 and not kwargs and isinstance(args[0], Message):
            request = args[0]
            if request._type != self.request_class._type:
                raise ServiceException(f"expected a {self.request_class._type} request, "
                                       f"got {request._type}")
        else:
            request = self.request_class(*args, **kwargs)
        body = request.serialize_bytes()
        with self._lock:
            conn = self._conn
            if conn is None:
                # a failed lookup or connection forgets where the service was: a node that
                # took over the port then sees at most one early connection, not one a call
                last, self._last_uri = self._last_uri, None
                conn = _open(self._rt.master, self.name, self._hello, last)
                self._last_uri = conn.uri
            try:
                ok, reply = conn.call(body, self._poll)
            except (OSError, TransportException) as exc:
                conn.close()
                self._conn = None
                raise ServiceException(f"service [{self.name}]: connection lost: {exc}") from exc
            if self.persistent:
                self._conn = conn
            else:
                conn.close()
        if not ok:
            raise ServiceException(f"service [{self.name}] responded with an error: "
                                   f"{reply.decode('utf-8', 'replace')}")
        return self.response_class.deserialize_bytes(reply)

    def close(self) -> None:
        with self._lock:
            if self._conn is not None:
                self._conn.close()
                self._conn = None

    def __del__(self):
        conn = getattr(self, "_conn", None)
        if conn is not None:
            conn.close()


def wait_for_service(service: str, timeout: float | None = None) -> None:
    """Block until ``service`` is registered and answers a probe; ``ROSException`` on
    timeout (``timeout``: seconds or a Duration, None to wait for ever). Works before
    ``init_node`` too, as in rospy."""
    rt = client_context()
    resolved = rt.resolve_name(service)
    if timeout is not None and not isinstance(timeout, (int, float)):
        timeout = timeout.to_sec()
    deadline = None if timeout is None else time.monotonic() + timeout
    delay = 0.01
    while True:
        if rt.is_shutdown():
            raise ROSInterruptException("rospy shutdown")
        try:
            uri = rt.master.call("lookupService", resolved)
            host, port = tcpros.parse_rosrpc_uri(uri)
            with tcpros.connect(host, port, timeout=1.0) as sock:
                tcpros.write_header(sock, {"callerid": rt.name, "service": resolved,
                                           "md5sum": "*", "probe": "1"})
                tcpros.read_header(sock)
            return
        except (MasterError, OSError, TransportException, ROSException):
            pass
        if deadline is not None and time.monotonic() >= deadline:
            raise ROSException(f"timeout exceeded while waiting for service {resolved}")
        time.sleep(delay if deadline is None else max(0.0, min(delay, deadline - time.monotonic())))
        delay = min(delay * 2, 0.2)
