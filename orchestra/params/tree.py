"""The parameter tree: rosmaster's parameter server semantics, without the network.

ROS stores parameters as one nested dict: a namespace *is* a dict, so getting ``/a`` returns
the whole ``{b: ..., c: ...}`` subtree, and setting ``/a`` to a dict replaces the subtree (it
does not merge; merging is a client-side habit of ``rosparam set``/``load``). Subscribers
(``subscribeParam``) are keyed by namespace-style names with a trailing ``/`` so that a
prefix test tells whether an update concerns them; a set or delete returns the list of
``ParamUpdate``s to deliver, and the caller (the master) does the I/O. Keeping the tree free
of sockets makes it testable in microseconds and usable in-process (``MasterHandle.params``).

Values must be ones XML-RPC can carry, because every other ROS client will read them over
XML-RPC: 32-bit ints, floats, bools, str, bytes/Binary, datetime, lists and str-keyed dicts;
no None. ``check_value`` says which name holds the offending value.
"""
from __future__ import annotations

import datetime
import threading
import xmlrpc.client
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from typing import Any

from orchestra.errors import Location, OrchestraError
from orchestra.names import canonicalize, namespace, ns_join

SEP = "/"
INT32_MIN = -(2 ** 31)
INT32_MAX = 2 ** 31 - 1


class ParamValueError(OrchestraError):
    """A value the parameter server cannot hold (it could not travel over XML-RPC)."""


# --- names (the shared graph-name rules, plus the master's caller-relative resolution) ----

canonical = canonicalize
namespace_of = namespace


def resolve(name: str, caller_id: str) -> str:
    """Resolve ``name`` as rosmaster does for a call made by node ``caller_id``.

    Relative names resolve in the caller's namespace, ``~x`` in the caller's own namespace
    (``/ns/node/x``), and an empty name means the caller's namespace.
    """
    if not name:
        return namespace_of(caller_id)
    name = canonical(name)
    if name.startswith(SEP):
        return name
    if name.startswith("~"):
        return canonical(caller_id + SEP + name[1:])
    return namespace_of(caller_id) + name


def _parts(key: str) -> list[str]:
    return [p for p in key.split(SEP) if p]


# --- values ----------------------------------------------------------------------------------

_SCALARS = (bool, float, str, bytes, bytearray, xmlrpc.client.Binary, datetime.datetime,
            xmlrpc.client.DateTime)


def check_value(name: str, value: Any, location: Location | None = None) -> None:
    """Raise ParamValueError naming the (sub-)parameter whose value XML-RPC cannot carry."""
    if isinstance(value, bool) or isinstance(value, _SCALARS):
        return
    if isinstance(value, int):
        if not INT32_MIN <= value <= INT32_MAX:
            raise ParamValueError(
                f"parameter '{name}': integer {value} does not fit in 32 bits "
                f"(XML-RPC carries {INT32_MIN}..{INT32_MAX}); quote it to store a string "
                "or write it as a float", location)
        return
    if value is None:
        raise ParamValueError(f"parameter '{name}' has no value (None/null cannot be stored "
                              "on the parameter server)", location)
    if isinstance(value, dict):
        for key, sub in value.items():
            if not isinstance(key, str):
                raise ParamValueError(f"parameter '{name}': dictionary key {key!r} is not a "
                                      "string", location)
            check_value(ns_join(name, key) if name != SEP else SEP + key, sub, location)
        return
    if isinstance(value, (list, tuple)):
        for index, sub in enumerate(value):
            check_value(f"{name}[{index}]", sub, location)
        return
    raise ParamValueError(f"parameter '{name}': a value of type {type(value).__name__} "
                          "cannot be stored on the parameter server", location)


def _copy_dicts(value: Any) -> Any:
    """Copy the dict skeleton of a value: the tree mutates dicts in place, never lists."""
    if not isinstance(value, dict):
        return value
    copy = value.copy()
    for k, v in copy.items():
        if isinstance(v, dict):
            copy[k] = _copy_dicts(v)
    return copy


# --- subscriptions ---------------------------------------------------------------------------

@dataclass(frozen=True)
class ParamUpdate:
    """One ``paramUpdate`` to deliver: to these (caller_id, caller_api) nodes, key and value.

    ``key`` keeps the subscription-style trailing ``/`` as rosmaster sends it; a deleted
    parameter is announced with the value ``{}``.
    """

    subscribers: tuple[tuple[str, str], ...]
    key: str
    value: Any


def subscription_key(key: str) -> str:
    """Subscription keys are namespace-style: canonical name plus a trailing ``/``."""
    if key == SEP:
        return SEP
    return canonical(key) + SEP


def _all_keys(prefix: str, value: dict) -> Iterator[str]:
    """Every namespace-style key below ``prefix`` that a dict value defines."""
    for k, v in value.items():
        key = prefix + k + SEP
        yield key
        if isinstance(v, dict):
            yield from _all_keys(key, v)


# --- the tree --------------------------------------------------------------------------------

class ParamTree:
    """A thread-safe hierarchical parameter store with rosmaster's exact semantics.

    All methods take global names. Reads return copies of dict subtrees, so a caller may
    keep, marshal or mutate a result while other threads write. ``listener`` (the master's
    notifier) receives the updates of every write, in write order, whoever made the write:
    an in-process ``tree.set`` reaches subscribed nodes just like an XML-RPC ``setParam``.
    """

    def __init__(self, listener: Callable[[list[ParamUpdate]], None] | None = None) -> None:
        self._root: dict[str, Any] = {}
        self._subscribers: dict[str, list[tuple[str, str]]] = {}
        self._lock = threading.RLock()
        self.listener = listener

    # reads -----------------------------------------------------------------------------------

    def _lookup(self, key: str) -> Any:
        value: Any = self._root
        for part in _parts(key):
            if not isinstance(value, dict) or part not in value:
                raise KeyError(key)
            value = value[part]
        return value

    def get(self, key: str) -> Any:
        """The value at ``key`` (a dict for a namespace); KeyError when it is not set."""
        with self._lock:
            return _copy_dicts(self._lookup(key))

    def has(self, key: str) -> bool:
        with self._lock:
            try:
                self._lookup(key)
            except KeyError:
                return False
            return True

    def names(self) -> list[str]:
        """Full names of every leaf parameter (an empty dict is not a parameter)."""
        out: list[str] = []

        def walk(prefix: str, d: dict) -> None:
            for k, v in d.items():
                if isinstance(v, dict):
                    walk(prefix + k + SEP, v)
                else:
                    out.append(prefix + k)

        with self._lock:
            walk(SEP, self._root)
        return out

    def search(self, ns: str, key: str) -> str | None:
        """rosmaster's searchParam: the full name of the closest ``key`` above ``ns``.

        Only the first segment of ``key`` must exist to match (``searchParam('a/b')`` finds
        the closest ``a``). ``ns`` itself is tried first, then each ancestor up to ``/``;
        rosmaster passes the caller id as ``ns``, so a node's private namespace comes first.
        """
        if key.startswith("~"):
            raise ValueError("private names cannot be used in search")
        if not key:
            return None
        if key.startswith(SEP):
            return key if self.has(key) else None
        first = _parts(key)[0]
        if self.has(ns_join(ns, first)):
            return ns_join(ns, key)
        ns_parts = _parts(ns)
        for cut in range(1, len(ns_parts) + 1):
            prefix = ns_parts[: len(ns_parts) - cut]
            if self.has(SEP + SEP.join(prefix + [first])):
                return SEP + SEP.join(prefix + [key])
        return None

    # writes ----------------------------------------------------------------------------------

    def set(self, key: str, value: Any) -> list[ParamUpdate]:
        """Store ``value`` at ``key`` (replacing any subtree); return the updates to deliver.

        Setting ``/`` requires a dict and replaces the whole tree. Missing intermediate
        namespaces are created, and a leaf in the way is replaced by a namespace.
        """
        value = _copy_dicts(value)
        with self._lock:
            if key == SEP:
                if not isinstance(value, dict):
                    raise TypeError("cannot set root of parameter tree to non-dictionary")
                self._root = value
            else:
                parts = _parts(key)
                d = self._root
                for part in parts[:-1]:
                    child = d.get(part)
                    if not isinstance(child, dict):
                        child = d[part] = {}
                    d = child
                d[parts[-1]] = value
            return self._announce(self._updates(key, value))

    def delete(self, key: str) -> list[ParamUpdate]:
        """Remove ``key`` (a leaf or a whole namespace); KeyError when it is not set."""
        if key == SEP or not _parts(key):
            raise KeyError("cannot delete root of parameter tree")
        with self._lock:
            parts = _parts(key)
            d: object = self._root
            for part in parts[:-1]:
                d = d.get(part) if isinstance(d, dict) else None
                if not isinstance(d, dict):
                    raise KeyError(key)
            if not isinstance(d, dict) or parts[-1] not in d:
                raise KeyError(key)
            del d[parts[-1]]
            return self._announce(self._updates(key, {}))

    # subscriptions ---------------------------------------------------------------------------

    def subscribe(self, key: str, caller_id: str, caller_api: str) -> Any:
        """Register a subscriber; return the current value, or ``{}`` when it is not set."""
        sub = subscription_key(key)
        with self._lock:
            try:
                value = self.get(sub)
            except KeyError:
                value = {}
            nodes = self._subscribers.setdefault(sub, [])
            if (caller_id, caller_api) not in nodes:
                nodes.append((caller_id, caller_api))
            return value

    def unsubscribe(self, key: str, caller_id: str, caller_api: str) -> bool:
        """Drop a subscription; False when there was none."""
        sub = subscription_key(key)
        with self._lock:
            nodes = self._subscribers.get(sub, [])
            if (caller_id, caller_api) not in nodes:
                return False
            nodes.remove((caller_id, caller_api))
            if not nodes:
                del self._subscribers[sub]
            return True

    def unsubscribe_all(self, caller_id: str) -> None:
        """Forget every subscription of a node (it was replaced by a namesake)."""
        with self._lock:
            for sub in list(self._subscribers):
                nodes = [n for n in self._subscribers[sub] if n[0] != caller_id]
                if nodes:
                    self._subscribers[sub] = nodes
                else:
                    del self._subscribers[sub]

    def subscriptions(self, caller_id: str) -> list[str]:
        """The keys a node is subscribed to (used to tell whether a node is still known)."""
        with self._lock:
            return [k for k, nodes in self._subscribers.items()
                    if any(n[0] == caller_id for n in nodes)]

    def _announce(self, updates: list[ParamUpdate]) -> list[ParamUpdate]:
        if updates and self.listener is not None:
            self.listener(updates)
        return updates

    def _updates(self, key: str, value: Any) -> list[ParamUpdate]:
        """The paramUpdates a write of ``value`` at ``key`` causes (rosmaster's rules).

        A subscriber hears about a write at or below its key with the written key and value;
        a subscriber below a written dict whose key the new dict no longer contains hears
        that its parameter is gone (``{}``); a subscriber at a key inside the written dict
        hears its own new sub-value.
        """
        if not self._subscribers:
            return []
        param_key = subscription_key(key)
        if not isinstance(value, dict):
            # a leaf reaches only subscriptions at or above it: its own key's prefixes, looked
            # up one by one (O(depth), not O(subscriptions) per setParam)
            updates: list[ParamUpdate] = []
            end = param_key.find(SEP) + 1
            while end:
                nodes = self._subscribers.get(param_key[:end])
                if nodes:
                    updates.append(ParamUpdate(tuple(nodes), param_key, value))
                end = param_key.find(SEP, end) + 1
            return updates
        inner = list(_all_keys(param_key, value))
        inner_set = set(inner)
        updates = []
        for sub, nodes in self._subscribers.items():
            if param_key.startswith(sub):
                updates.append(ParamUpdate(tuple(nodes), param_key, _copy_dicts(value)))
            elif sub.startswith(param_key) and sub not in inner_set:
                updates.append(ParamUpdate(tuple(nodes), sub, {}))
        for sub in inner:
            listeners = self._subscribers.get(sub)
            if listeners:
                sub_value = value
                for part in _parts(sub[len(param_key):]):
                    sub_value = sub_value[part]
                updates.append(ParamUpdate(tuple(listeners), sub, _copy_dicts(sub_value)))
        return updates
