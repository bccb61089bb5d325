"""The launch's XML-RPC endpoint, registered on the master as ``/roslaunch/uris/host_<h>__<port>``.

roslaunch serves a small XML-RPC API and records its URI under ``/roslaunch/uris`` so tools
can find the launches of a ROS graph; orchestra does the same, answering roslaunch's
read-only calls (``getPid``, ``list_processes``, ``process_info``, ``get_node_names``) plus
``orchestra_status`` (the snapshot ``orchestra status`` prints). It is served from the
supervisor's own loop, one request at a time with a short socket timeout, so answers always
see a consistent state and no thread touches the supervisor.
"""
from __future__ import annotations

import json
import logging
import os
import re
import socket
from collections.abc import Callable
from typing import Any

from orchestra.rpc import PolledServer
from orchestra.supervise.loop import EventLoop
from orchestra.supervise.process import ManagedProcess, State

logger = logging.getLogger(__name__)


def uris_param(host: str, port: int) -> str:
    """roslaunch's parameter name for a launch server: ``/roslaunch/uris/host_my_pc__40123``."""
    return f"/roslaunch/uris/host_{re.sub(r'[^A-Za-z0-9_]', '_', host)}__{port}"


def advertised_host(bound_to_loopback: bool) -> str:
    """The host name put in our URI: ROS_HOSTNAME, ROS_IP, else what the bind allows."""
    for key in ("ROS_HOSTNAME", "ROS_IP"):
        if os.environ.get(key):
            return os.environ[key]
    return "localhost" if bound_to_loopback else socket.gethostname()


def _xmlrpc_safe(doc: dict[str, Any]) -> dict[str, Any]:
    """Ints past XML-RPC's 32-bit limit (RSS) as floats; None kept (allow_none)."""
    return {k: float(v) if isinstance(v, int) and not isinstance(v, bool)
            and abs(v) > 2**31 - 1 else v for k, v in doc.items()}


class LaunchRPCServer:
    def __init__(self, loop: EventLoop, procs: list[ManagedProcess],
                 make_snapshot: Callable[[], dict[str, Any]], loopback: bool = True):
        bind = "127.0.0.1" if loopback else "0.0.0.0"
        self._server = PolledServer((bind, 0), allow_none=True)
        self.port = self._server.port
        self.host = advertised_host(loopback)
        self.uri = f"http://{self.host}:{self.port}/"
        self._procs = procs
        self._make = make_snapshot
        for name in ("getPid", "list_processes", "process_info", "get_node_names",
                     "orchestra_status"):
            self._server.register_function(getattr(self, name), name)
        self._loop = loop
        loop.add_reader(self._server.fileno(), self._handle)

    def _handle(self) -> None:
        try:
            self._server.handle_ready()
        except OSError as exc:  # pragma: no cover - a client that went away
            logger.debug("launch rpc: %s", exc)

    # --- roslaunch's API (caller_id first, (code, message, value) answers)

    def getPid(self, caller_id: str) -> list[Any]:
        return [1, "", os.getpid()]

    def list_processes(self, caller_id: str) -> list[Any]:
        running = [p.spec.name for p in self._procs
                   if p.state in (State.RUNNING, State.STOPPING, State.BACKOFF)]
        finished = [[p.spec.name, p.restarts + 1] for p in self._procs
                    if p.state in (State.EXITED, State.FAILED)]
        return [1, "processes on parent machine", [running, finished]]

    def process_info(self, caller_id: str, name: str) -> list[Any]:
        for doc in self._make()["nodes"]:
            if doc["name"] == name:
                return [1, "process info", _xmlrpc_safe(doc)]
        return [-1, f"no process named {name}", {}]

    def get_node_names(self, caller_id: str) -> list[Any]:
        return [1, "", [p.spec.name for p in self._procs]]

    def orchestra_status(self, caller_id: str) -> list[Any]:
        """The snapshot as a JSON string (XML-RPC ints stop at 2**31, RSS does not)."""
        return [1, "", json.dumps(self._make())]

    def close(self) -> None:
        self._loop.remove_reader(self._server.fileno())
        self._server.server_close()
