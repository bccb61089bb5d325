"""The XML-RPC transport of the master: a threaded stdlib server with keep-alive.

One thread per connection (``ThreadingMixIn``); HTTP/1.1 so that clients which keep their
connection open (xmlrpc.client does) pay the TCP set-up once. Open connections are tracked so
``close()`` really ends them: an idle keep-alive connection must not keep a thread, or a
port, alive after the master is gone.
"""
from __future__ import annotations

import os
import socket
import threading

from orchestra.rpc import AnyPathHandler, ThreadedServer

LOCALHOST_NAMES = ("localhost", "127.0.0.1", "::1")


class _Handler(AnyPathHandler):
    protocol_version = "HTTP/1.1"
    # an idle keep-alive connection is closed after this long (seconds)
    timeout = 60


class ThreadedXMLRPCServer(ThreadedServer):
    """The shared threaded server, with HTTP/1.1 keep-alive and connections tracked."""

    block_on_close = False
    request_queue_size = 128

    def __init__(self, addr: tuple[str, int]):
        super().__init__(addr, handler=_Handler)
        self._connections: set[socket.socket] = set()
        self._conn_lock = threading.Condition()

    def process_request(self, request, client_address):
        with self._conn_lock:
            self._connections.add(request)
        super().process_request(request, client_address)

    def shutdown_request(self, request):
        super().shutdown_request(request)
        with self._conn_lock:
            self._connections.discard(request)
            self._conn_lock.notify_all()

    def close_connections(self, grace: float = 2.0) -> None:
        """End every open client connection (their handler threads then exit).

        Only the read side is shut: a handler blocked waiting for the next keep-alive
        request sees end-of-file at once, while one still answering (e.g. the ``shutdown``
        call that triggered this) can finish writing its reply; we wait up to ``grace``
        seconds for those.
        """
        with self._conn_lock:
            connections = list(self._connections)
        for conn in connections:
            try:
                conn.shutdown(socket.SHUT_RD)
            except OSError:
                pass
        with self._conn_lock:
            self._conn_lock.wait_for(lambda: not self._connections, grace)


def bind_address(host: str | None = None, environ: dict[str, str] | None = None
                 ) -> tuple[str, str]:
    """(address to bind, host name to advertise in URIs) for a master.

    Default is loopback only: a master reachable from the network lets anyone start and stop
    nodes. An explicit ``host`` wins; otherwise ROS_IP / ROS_HOSTNAME (ROS's own way to say
    "reachable from elsewhere") open it on all interfaces, advertised under that name.
    """
    env = os.environ if environ is None else environ
    if host:
        advertised = host if host not in ("0.0.0.0", "::", "") else socket.gethostname()
        return host, advertised
    public = env.get("ROS_HOSTNAME") or env.get("ROS_IP")
    if public and public not in LOCALHOST_NAMES:
        return "0.0.0.0", public
    return "127.0.0.1", "127.0.0.1"
