"""Who publishes, subscribes to and provides what: the master's graph bookkeeping.

Pure data with rosmaster's rules; the API layer (``api.py``) validates arguments and turns
results into ``[code, message, value]``, and the notifier does the network calls. A node is
known by ``caller_id`` with one slave API URI; when the same name registers from a different
URI, the old registration is dropped entirely and the old URI is reported back so that the
caller can tell that process to shut down (roslaunch's "new node registered with same name").
"""
from __future__ import annotations

import threading
from dataclasses import dataclass, field

PUBLISHER = "publisher"
SUBSCRIBER = "subscriber"
SERVICE = "service"
PARAM_SUBSCRIBER = "param_subscriber"
ANYTYPE = "*"


@dataclass
class NodeRef:
    """A registered node: its slave API and what it registered (to forget it when empty)."""

    caller_id: str
    api: str
    keys: dict[str, set[str]] = field(default_factory=lambda: {
        PUBLISHER: set(), SUBSCRIBER: set(), SERVICE: set(), PARAM_SUBSCRIBER: set()})

    def is_empty(self) -> bool:
        return not any(self.keys.values())


class Registrations:
    """Thread-safe registries of publishers, subscribers, services and topic types.

    ``topics[kind][topic]`` keeps (caller_id, caller_api) pairs in registration order,
    because publisherUpdate lists and getSystemState show them in that order.
    """

    def __init__(self) -> None:
        self.lock = threading.RLock()
        self.nodes: dict[str, NodeRef] = {}
        self.topics: dict[str, dict[str, list[tuple[str, str]]]] = {
            PUBLISHER: {}, SUBSCRIBER: {}, PARAM_SUBSCRIBER: {}}
        # service name -> (caller_id, caller_api, service_api)
        self.services: dict[str, tuple[str, str, str]] = {}
        self.topic_types: dict[str, str] = {}

    # nodes -----------------------------------------------------------------------------------

    def _node(self, caller_id: str, caller_api: str) -> tuple[NodeRef, str | None]:
        """The node's ref, replacing a namesake at another URI; returns (ref, bumped_api)."""
        ref = self.nodes.get(caller_id)
        if ref is not None and ref.api == caller_api:
            return ref, None
        bumped = ref.api if ref is not None else None
        if ref is not None:
            self._forget(caller_id)
        ref = NodeRef(caller_id, caller_api)
        self.nodes[caller_id] = ref
        return ref, bumped

    def _forget(self, caller_id: str) -> None:
        """Drop every registration of a node."""
        for registry in self.topics.values():
            for key in list(registry):
                remaining = [p for p in registry[key] if p[0] != caller_id]
                if remaining:
                    registry[key] = remaining
                else:
                    del registry[key]
        for name in [s for s, v in self.services.items() if v[0] == caller_id]:
            del self.services[name]
        self.nodes.pop(caller_id, None)

    def register(self, kind: str, key: str, caller_id: str, caller_api: str,
                 service_api: str | None = None) -> str | None:
        """Record a registration; returns the slave URI of a replaced namesake, if any."""
        with self.lock:
            ref, bumped = self._node(caller_id, caller_api)
            ref.keys[kind].add(key)
            if kind == SERVICE:
                assert service_api is not None
                self.services[key] = (caller_id, caller_api, service_api)
            else:
                providers = self.topics[kind].setdefault(key, [])
                if (caller_id, caller_api) not in providers:
                    providers.append((caller_id, caller_api))
            return bumped

    def unregister(self, kind: str, key: str, caller_id: str, caller_api: str | None = None,
                   service_api: str | None = None) -> tuple[int, str, int]:
        """rosmaster's unregister result: (1, message, 1 if something was removed else 0)."""
        with self.lock:
            ref = self.nodes.get(caller_id)
            if ref is None:
                return 1, f"[{caller_id}] is not a registered node", 0
            if kind == SERVICE:
                current = self.services.get(key)
                if current is None or (current[0], current[2]) != (caller_id, service_api):
                    result = (1, f"[{service_api}] is no longer the current service api "
                                 f"handle for [{key}]", 0)
                else:
                    del self.services[key]
                    result = (1, f"Unregistered [{caller_id}] as provider of [{key}]", 1)
            else:
                providers = self.topics[kind].get(key, [])
                if caller_api is not None and (caller_id, caller_api) in providers:
                    providers.remove((caller_id, caller_api))
                    if not providers:
                        del self.topics[kind][key]
                    result = (1, f"Unregistered [{caller_id}] as provider of [{key}]", 1)
                else:
                    result = (1, f"[{caller_id}] is not a known provider of [{key}]", 0)
            if result[2] == 1:
                ref.keys[kind].discard(key)
            if ref.is_empty():
                del self.nodes[caller_id]
            return result

    # queries ---------------------------------------------------------------------------------

    def apis(self, kind: str, topic: str) -> list[str]:
        """Slave URIs of the publishers or subscribers of a topic, in registration order."""
        with self.lock:
            return [api for _, api in self.topics[kind].get(topic, [])]

    def node_api(self, caller_id: str) -> str | None:
        with self.lock:
            ref = self.nodes.get(caller_id)
            return ref.api if ref is not None else None

    def service_api(self, service: str) -> str | None:
        with self.lock:
            entry = self.services.get(service)
            return entry[2] if entry is not None else None

    def system_state(self) -> list[list[list]]:
        """getSystemState's value: [publishers, subscribers, services], each [[name, [ids]]]."""
        with self.lock:
            pubs = [[t, [c for c, _ in p]] for t, p in self.topics[PUBLISHER].items()]
            subs = [[t, [c for c, _ in p]] for t, p in self.topics[SUBSCRIBER].items()]
            srvs = [[s, [v[0]]] for s, v in self.services.items()]
            return [pubs, subs, srvs]
