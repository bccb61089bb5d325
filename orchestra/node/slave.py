"""The node's slave XML-RPC API: how the master and tools talk to a running node.

Method names and return shapes are ROS 1's (``[code, statusMessage, value]``), so rosnode,
rostopic and rosmaster work against orchestra nodes and orchestra's tools against ROS nodes.
The server is threaded so a slow call (e.g. ``shutdown``) never blocks ``publisherUpdate``.
"""
from __future__ import annotations

import logging
import os
import threading
from typing import TYPE_CHECKING, Any

from orchestra.rpc import ThreadedServer

if TYPE_CHECKING:
    from orchestra.node.runtime import NodeRuntime

log = logging.getLogger(__name__)


class SlaveAPI:
    """The methods exposed over XML-RPC; each delegates to the node runtime."""

    def __init__(self, runtime: NodeRuntime):
        self._rt = runtime

    def getBusStats(self, caller_id: str) -> list:
        return [1, "", self._rt.bus_stats()]

    def getBusInfo(self, caller_id: str) -> list:
        return [1, "", self._rt.bus_info()]

    def getMasterUri(self, caller_id: str) -> list:
        return [1, "", self._rt.master_uri]

    def shutdown(self, caller_id: str, msg: str = "") -> list:
        log.info("shutdown requested by %s: %s", caller_id, msg)
        self._rt.signal_shutdown(f"shutdown request from {caller_id}: {msg}" if msg
                                 else f"shutdown request from {caller_id}")
        return [1, "shutdown", 0]

    def getPid(self, caller_id: str) -> list:
        return [1, "", os.getpid()]

    def getSubscriptions(self, caller_id: str) -> list:
        return [1, "subscriptions", self._rt.topics.subscription_list()]

    def getPublications(self, caller_id: str) -> list:
        return [1, "publications", self._rt.topics.publication_list()]

    def paramUpdate(self, caller_id: str, key: str, value: Any) -> list:
        self._rt.param_updated(key, value)
        return [1, "", 0]

    def publisherUpdate(self, caller_id: str, topic: str, publishers: list) -> list:
        self._rt.topics.publisher_update(topic, list(publishers))
        return [1, "", 0]

    def requestTopic(self, caller_id: str, topic: str, protocols: list) -> list:
        if not self._rt.topics.has_publication(topic):
            return [-1, f"Not a publisher of [{topic}]", []]
        for proto in protocols:
            if proto and proto[0] == "TCPROS":
                host, port = self._rt.tcpros_address
                return [1, f"ready on {host}:{port:d}", ["TCPROS", host, port]]
        return [0, "no supported protocol implementations", []]


class SlaveServer:
    """An XML-RPC server on an ephemeral port, serving ``SlaveAPI`` from a daemon thread."""

    def __init__(self, runtime: NodeRuntime, bind_host: str, advertise_host: str, port: int = 0):
        self._server = ThreadedServer((bind_host, port))
        self._server.register_instance(SlaveAPI(runtime))
        self.port = self._server.server_address[1]
        self.uri = f"http://{advertise_host}:{self.port}/"
        self._thread = threading.Thread(target=self._server.serve_forever,
                                        kwargs={"poll_interval": None},
                                        name="slave-xmlrpc", daemon=True)

    def start(self) -> None:
        self._thread.start()

    def stop(self) -> None:
        self._server.shutdown()
        self._server.server_close()
