"""Reading the ROS graph from a master (orchestra's or a real one) and from nodes' slave APIs.

Pure data in, pure data out: ``SystemState`` is the master's ``getSystemState`` answer with
the topic types added; the CLI and the graph drawer only format it.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field

from orchestra.errors import OrchestraError
from orchestra.node import tcpros
from orchestra.node.exceptions import TransportException
from orchestra.node.masterapi import MasterError, call, raw_call

CALLER = "/orchestra_cli"


class GraphError(OrchestraError):
    """Something asked about the graph does not exist (unknown node, topic or service)."""


def master_call(master_uri: str, method: str, *args):
    """A master call from the CLI: unreachable master -> MasterUnreachable (exit 1)."""
    from orchestra.rpc import MasterUnreachable

    try:
        code, msg, value = raw_call(master_uri, method, CALLER, *args, timeout=5.0)
    except MasterError as exc:
        raise MasterUnreachable(f"cannot contact the master at {master_uri}: {exc}") from None
    if code != 1:
        raise GraphError(msg)
    return value


@dataclass
class SystemState:
    publishers: dict[str, list[str]] = field(default_factory=dict)   # topic -> nodes
    subscribers: dict[str, list[str]] = field(default_factory=dict)  # topic -> nodes
    services: dict[str, list[str]] = field(default_factory=dict)     # service -> nodes
    types: dict[str, str] = field(default_factory=dict)              # topic -> type

    @property
    def nodes(self) -> list[str]:
        found: set[str] = set()
        for table in (self.publishers, self.subscribers, self.services):
            for names in table.values():
                found.update(names)
        return sorted(found)

    @property
    def topics(self) -> list[str]:
        return sorted(set(self.publishers) | set(self.subscribers))

    def node_publications(self, node: str) -> list[str]:
        return sorted(t for t, ns in self.publishers.items() if node in ns)

    def node_subscriptions(self, node: str) -> list[str]:
        return sorted(t for t, ns in self.subscribers.items() if node in ns)

    def node_services(self, node: str) -> list[str]:
        return sorted(s for s, ns in self.services.items() if node in ns)


def system_state(master_uri: str) -> SystemState:
    pubs, subs, srvs = master_call(master_uri, "getSystemState")
    types = dict(master_call(master_uri, "getTopicTypes"))
    return SystemState({t: list(n) for t, n in pubs}, {t: list(n) for t, n in subs},
                       {s: list(n) for s, n in srvs}, types)


def lookup_node(master_uri: str, node: str) -> str:
    try:
        return master_call(master_uri, "lookupNode", node)
    except GraphError:
        raise GraphError(f"unknown node [{node}]") from None


def node_bus_info(node_uri: str) -> tuple[int | None, list]:
    """(pid, bus info rows) from a node's slave API; (None, []) when it does not answer."""
    try:
        pid = call(node_uri, "getPid", CALLER, timeout=2.0)
        info = call(node_uri, "getBusInfo", CALLER, timeout=2.0)
    except MasterError:
        return None, []
    return pid, info


def kill_node(master_uri: str, node: str, settle: float = 2.0) -> None:
    """Ask ``node`` to shut down through its slave API.

    rospy tears its XML-RPC server down while still handling ``shutdown``, so the reply is
    often lost (the connection drops, and xmlrpc.client's one retry is refused). rosnode
    therefore assumes success whatever happens; we check instead: a node that answered
    before the request and stops answering within ``settle`` seconds has been killed.
    """
    uri = lookup_node(master_uri, node)
    try:
        call(uri, "getPid", CALLER, timeout=2.0)
    except MasterError as exc:
        raise GraphError(f"node [{node}] does not answer at {uri}: {exc}") from None
    try:
        call(uri, "shutdown", CALLER, "user request", timeout=5.0)
        return
    except MasterError as exc:
        failure = exc
    if failure.code is None and _stops_answering(uri, settle):
        return
    raise GraphError(f"node [{node}] did not accept the shutdown request: {failure}")


def _stops_answering(uri: str, within: float) -> bool:
    deadline = time.monotonic() + within
    while True:
        try:
            call(uri, "getPid", CALLER, timeout=1.0)
        except MasterError as exc:
            if exc.code is None:
                return True
        if time.monotonic() >= deadline:
            return False
        time.sleep(0.05)


def service_uri(master_uri: str, service: str) -> str:
    try:
        return master_call(master_uri, "lookupService", service)
    except GraphError:
        raise GraphError(f"service [{service}] is not available") from None


def service_header(master_uri: str, service: str) -> dict[str, str]:
    """The service's connection header, obtained with a ``probe`` connection (as rosservice)."""
    uri = service_uri(master_uri, service)
    host, port = tcpros.parse_rosrpc_uri(uri)
    try:
        with tcpros.connect(host, port, timeout=5.0) as sock:
            tcpros.write_header(sock, {"callerid": CALLER, "service": service, "md5sum": "*",
                                       "probe": "1"})
            header = tcpros.read_header(sock)
    except (OSError, TransportException) as exc:
        raise GraphError(f"service [{service}] at {uri} does not answer: {exc}") from None
    if "error" in header:
        raise GraphError(f"service [{service}]: {header['error']}")
    return header


def ping_node(master_uri: str, node: str) -> tuple[str, float | None]:
    """(slave URI, round-trip seconds of ``getPid``), None when the node does not answer."""
    import time

    uri = lookup_node(master_uri, node)
    start = time.monotonic()
    try:
        call(uri, "getPid", CALLER, timeout=2.0)
    except MasterError:
        return uri, None
    return uri, time.monotonic() - start


def unreachable_nodes(master_uri: str, state: SystemState) -> list[str]:
    """Nodes the master lists whose slave API does not answer (died without unregistering)."""
    dead = []
    for node in state.nodes:
        try:
            _, rtt = ping_node(master_uri, node)
        except GraphError:
            continue
        if rtt is None:
            dead.append(node)
    return dead


def purge_node(master_uri: str, state: SystemState, node: str) -> None:
    """Unregister everything ``node`` registered, on its behalf (rosnode cleanup)."""
    api = lookup_node(master_uri, node)
    for topic in state.node_publications(node):
        raw_call(master_uri, "unregisterPublisher", node, topic, api, timeout=5.0)
    for topic in state.node_subscriptions(node):
        raw_call(master_uri, "unregisterSubscriber", node, topic, api, timeout=5.0)
    for service in state.node_services(node):
        try:
            uri = master_call(master_uri, "lookupService", service)
        except GraphError:
            continue
        raw_call(master_uri, "unregisterService", node, service, uri, timeout=5.0)
