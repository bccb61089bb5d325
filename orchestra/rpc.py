"""XML-RPC plumbing shared by the master, node slave APIs, the launch server and the tools.

ROS 1 speaks XML-RPC everywhere: nodes register with the master, the master notifies nodes,
tools query both. The pieces every one of them needs (a threaded server that accepts any
request path, a client transport that gives up after a timeout, the default master address,
the errors that mean "nobody answered") are defined once here, at the bottom of the layer
picture, so master, node and supervise cannot drift apart (and need not import each other).
"""
from __future__ import annotations

import logging
import os
import socket
import socketserver
import xmlrpc.client
from collections.abc import Iterable, Mapping
from http.client import HTTPConnection, HTTPException
from typing import Any, cast
from xmlrpc.server import SimpleXMLRPCRequestHandler, SimpleXMLRPCServer

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

class TimeoutTransport(xmlrpc.client.Transport):
    """An XML-RPC transport whose connections give up after ``timeout`` seconds.

    xmlrpc.client has no timeout of its own: a peer that accepts and never answers (a
    stopped node, a wedged master) would block the caller forever.
    """

    def __init__(self, timeout: float):
        super().__init__()
        self.timeout = timeout

    def make_connection(self, host: Any) -> HTTPConnection:
        conn = super().make_connection(host)
        conn.timeout = self.timeout
        return conn


def proxy(uri: str, timeout: float | None = None) -> xmlrpc.client.ServerProxy:
    """An XML-RPC proxy for ``uri``; ``timeout`` bounds each call (None = wait forever).

    A proxy keeps one HTTP connection and is not thread-safe: make one per thread (on
    loopback a connect costs tens of microseconds).
    """
    transport = TimeoutTransport(timeout) if timeout is not None else None
    return xmlrpc.client.ServerProxy(uri, transport=transport)


def call(uri: str, method: str, *args: Any, timeout: float | None = None) -> Any:
    """``method(*args)`` at ``uri`` on a connection of its own, closed afterwards (a
    proxy otherwise holds its socket until it is garbage-collected)."""
    with proxy(uri, timeout) as server:
        return getattr(server, method)(*args)


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

class AnyPathHandler(SimpleXMLRPCRequestHandler):
    """Accepts a call posted to any path: rospy and roscpp post to "/", others to "/RPC2"."""

    rpc_paths = ()

    def log_message(self, format: str, *args: Any) -> None:  # noqa: A002 - http.server's name
        log.debug("%s " + format, self.address_string(), *args)


class ThreadedServer(socketserver.ThreadingMixIn, SimpleXMLRPCServer):
    """SimpleXMLRPCServer answering each connection in its own daemon thread.

    Threaded so that one slow call (a node's ``shutdown``, a master notifying a dead node)
    never blocks the others. IPv6 when the bind address is one.
    """

    daemon_threads = True
    allow_reuse_address = True

    def __init__(self, addr: tuple[str, int],
                 handler: type[SimpleXMLRPCRequestHandler] = AnyPathHandler,
                 allow_none: bool = False):
        self.address_family = socket.AF_INET6 if ":" in addr[0] else socket.AF_INET
        super().__init__(addr, requestHandler=handler, logRequests=False,
                         allow_none=allow_none, bind_and_activate=True)

    @property
    def port(self) -> int:
        return int(self.server_address[1])


class PolledServer(SimpleXMLRPCServer):
    """A single-threaded server driven by the caller's event loop: ``handle_ready`` answers
    one waiting request. A client gets ``client_timeout`` seconds to send it, so a slow or
    silent client cannot stall the loop."""

    def __init__(self, addr: tuple[str, int], allow_none: bool = False,
                 client_timeout: float = 2.0):
        super().__init__(addr, requestHandler=AnyPathHandler, logRequests=False,
                         allow_none=allow_none)
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
