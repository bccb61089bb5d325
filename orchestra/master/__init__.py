"""The ROS master (registration + parameter server) as a library.

``start_master()`` serves the ROS Master API from threads of the calling process and
returns at once: ``orchestra launch`` embeds it (no second interpreter start-up),
``orchestra core`` runs it standalone, tests start one per test on an ephemeral port.
"""
from __future__ import annotations

import logging
import os
import threading
import uuid
from typing import Any

from orchestra.errors import OrchestraError
from orchestra.master.api import MasterAPI
from orchestra.master.client import (
    DEFAULT_MASTER_URI,
    MasterUnreachable,
    master_is_up,
    master_uri_from_env,
    port_from_uri,
    upload_params,
)
from orchestra.master.notify import Notifier
from orchestra.master.server import ThreadedXMLRPCServer, bind_address
from orchestra.params.tree import ParamTree
from orchestra.rpc import DEFAULT_PORT

__all__ = [
    "DEFAULT_MASTER_URI", "MasterHandle", "MasterUnreachable", "bind_address",
    "core_params", "master_is_up", "master_uri_from_env", "port_from_uri", "start_master",
    "upload_params",
]

log = logging.getLogger(__name__)

# the ROS release whose master behaviour (and /rosversion) orchestra reproduces
EMULATED_ROS_VERSION = "1.16.0"


class MasterHandle:
    """A running in-process master: ``uri``, ``port``, ``params``, ``shutdown()``.

    ``shutdown()`` is idempotent and also runs when a client calls the master's
    ``shutdown`` method; ``wait()`` blocks until then (what ``orchestra core`` does).
    """

    def __init__(self, server: ThreadedXMLRPCServer, api: MasterAPI, uri: str):
        self._server = server
        self.api = api
        self.uri = uri
        self.port: int = server.server_address[1]
        self.params: ParamTree = api.params
        self.shutdown_reason: str | None = None
        self._stopped = threading.Event()
        self._stopping = False
        self._lock = threading.Lock()
        self._thread = threading.Thread(target=server.serve_forever, kwargs={"poll_interval": 0.1},
                                        name=f"master :{self.port}", daemon=True)

    def _start(self) -> None:
        self._thread.start()

    def shutdown(self, reason: str = "shutdown requested") -> None:
        """Stop serving, end open connections, free the port. Safe to call twice."""
        with self._lock:
            if self._stopping:
                self._stopped.wait()
                return
            self._stopping = True
            self.shutdown_reason = reason
        try:
            self._server.shutdown()  # waits for serve_forever to return (never our thread)
            self._server.close_connections()
            self._server.server_close()
            self.api.notifier.close()
        finally:
            self._stopped.set()
        log.info("master %s stopped: %s", self.uri, reason)

    def _remote_shutdown(self, reason: str) -> None:
        # an XML-RPC shutdown call runs in a request thread: stop from another thread so
        # the reply still goes out
        threading.Thread(target=self.shutdown, args=(reason,), daemon=True).start()

    def wait(self, timeout: float | None = None) -> bool:
        """Block until the master was shut down; False on timeout."""
        return self._stopped.wait(timeout)

    @property
    def running(self) -> bool:
        return not self._stopping

    def __enter__(self) -> MasterHandle:
        return self

    def __exit__(self, *exc: Any) -> None:
        self.shutdown()

    def __repr__(self) -> str:
        return f"MasterHandle({self.uri!r})"


def start_master(host: str = "127.0.0.1", port: int = DEFAULT_PORT,
                 advertise: str | None = None) -> MasterHandle:
    """Start a threaded master serving on ``host:port`` (0 = a free port); return at once.

    ``advertise`` is the host name put in ``uri`` (default: ``host``, or this machine's name
    when bound to all interfaces). A port in use is a user-facing OrchestraError.
    """
    try:
        server = ThreadedXMLRPCServer((host, port))
    except OSError as exc:
        raise OrchestraError(f"cannot start a master on {host}:{port}: {exc.strerror or exc}"
                             ) from None
    if advertise is None:
        advertise = bind_address(host)[1]
    bound_port = server.server_address[1]
    uri = f"http://{advertise}:{bound_port}/"
    api = MasterAPI(uri=uri, notifier=Notifier())
    server.register_instance(api)
    server.register_multicall_functions()
    handle = MasterHandle(server, api, uri)
    api.on_shutdown = handle._remote_shutdown
    handle._start()
    log.info("master serving at %s (pid %d)", uri, os.getpid())
    return handle


def core_params(run_id: str | None = None, environ: dict[str, str] | None = None
                ) -> dict[str, Any]:
    """What roscore puts on a fresh parameter server: /run_id, /rosdistro, /rosversion.

    roscore fills /rosdistro and /rosversion from command output, hence the trailing
    newlines, which tools compare against; we keep them.
    """
    env = os.environ if environ is None else environ
    return {
        "/run_id": run_id or str(uuid.uuid1()),
        "/rosdistro": (env.get("ROS_DISTRO") or "noetic") + "\n",
        "/rosversion": EMULATED_ROS_VERSION + "\n",
    }
