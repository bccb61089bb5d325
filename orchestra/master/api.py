"""The ROS Master API and Parameter Server API, answered exactly as rosmaster answers.

Every call takes ``caller_id`` first and returns ``[code, statusMessage, value]``: 1 success,
-1 caller error, 0 master failure. Argument checking mirrors rosmaster's validators (same
messages, same error values), so a client that parses messages sees no difference, and a
malformed call from any client gets an error triple instead of killing a server thread.
Names are resolved relative to the caller. Outgoing calls (publisherUpdate, paramUpdate,
shutdown of a replaced node) go through the ``Notifier`` and never block the reply.
"""
from __future__ import annotations

import logging
import os
import threading
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from orchestra.master.notify import MASTER_CALLER_ID, Notifier
from orchestra.master.registrations import (
    ANYTYPE,
    PARAM_SUBSCRIBER,
    PUBLISHER,
    SERVICE,
    SUBSCRIBER,
    Registrations,
)
from orchestra.params.tree import (
    SEP,
    ParamTree,
    ParamUpdate,
    ParamValueError,
    check_value,
    resolve,
    subscription_key,
)

log = logging.getLogger(__name__)

Result = tuple[int, str, Any]


class Invalid(Exception):
    """An argument failed validation; the message is rosmaster's."""


# --- validators: (value, caller_id) -> canonical value ----------------------------------------

Validator = Callable[[Any, str], Any]


def _non_empty_str(name: str) -> Validator:
    def check(value: Any, caller_id: str) -> Any:
        if not value:
            raise Invalid(f"ERROR: parameter [{name}] must be specified and non-empty")
        if not isinstance(value, str):
            raise Invalid(f"ERROR: parameter [{name}] must be a string")
        return value
    return check


def _not_none(name: str) -> Validator:
    def check(value: Any, caller_id: str) -> Any:
        if value is None:
            raise Invalid(f"ERROR: parameter [{name}] must be specified")
        return value
    return check


def _is_api(name: str) -> Validator:
    def check(value: Any, caller_id: str) -> Any:
        if not value or not isinstance(value, str):
            raise Invalid(f"ERROR: parameter [{name}] is not an XMLRPC URI")
        if not value.startswith(("http://", "rosrpc://")):
            raise Invalid(f"ERROR: parameter [{name}] is not an RPC URI")
        return value
    return check


def _graph_name(name: str, allow_root: bool = False) -> Validator:
    def check(value: Any, caller_id: str) -> Any:
        if not value or not isinstance(value, str):
            raise Invalid(f"ERROR: parameter [{name}] must be a non-empty string")
        if ":" in value or " " in value:
            raise Invalid(f"ERROR: parameter [{name}] contains illegal chars")
        if value == SEP and not allow_root:
            raise Invalid(f"ERROR: parameter [{name}] cannot be the global namespace")
        return resolve(value, caller_id)
    return check


def _empty_or_name(name: str) -> Validator:
    def check(value: Any, caller_id: str) -> Any:
        if not isinstance(value, str):
            raise Invalid(f"ERROR: parameter [{name}] must be a string")
        return resolve(value, caller_id) if value else ""
    return check


def _type_name(name: str) -> Validator:
    def check(value: Any, caller_id: str) -> Any:
        if value == ANYTYPE:
            return value
        if not value or not isinstance(value, str):
            raise Invalid(f"ERROR: parameter [{name}] must be a non-empty string")
        if len(value.split("/")) != 2:
            raise Invalid(f"ERROR: parameter [{name}] is not a valid package resource name")
        return value
    return check


@dataclass(frozen=True)
class _Spec:
    """How one API method is checked: its error value and per-argument validators."""

    error_value: Any
    validators: tuple[Validator | None, ...]
    optional: int = 0  # trailing arguments that may be omitted


def _api(error_value: Any, *validators: Validator | None, optional: int = 0):
    def mark(fn):
        fn._api_spec = _Spec(error_value, validators, optional)
        return fn
    return mark


class MasterAPI:
    """The master's state and its XML-RPC methods (dispatched by ``_dispatch``)."""

    def __init__(self, uri: str = "", notifier: Notifier | None = None,
                 params: ParamTree | None = None,
                 on_shutdown: Callable[[str], None] | None = None):
        self.uri = uri
        self.params = params if params is not None else ParamTree()
        self.params.listener = self._notify_params
        self.reg = Registrations()
        self.notifier = notifier if notifier is not None else Notifier()
        self.on_shutdown = on_shutdown
        # one lock orders registrations with the notifications they cause
        self._lock = threading.RLock()

    # dispatch --------------------------------------------------------------------------------

    def _dispatch(self, method: str, params: tuple) -> Any:
        """Validate and run one call; unknown methods are XML-RPC faults, as in rosmaster."""
        entry = _METHODS.get(method)
        if entry is None:
            raise Exception(f'method "{method}" is not supported')
        fn, spec = entry
        if len(params) == 0:
            return -1, "missing required caller_id parameter", spec.error_value
        n_args = len(spec.validators) + 1
        if not n_args - spec.optional <= len(params) <= n_args:
            return -1, "Error: bad call arity", spec.error_value
        caller_id = params[0]
        if not isinstance(caller_id, str):
            return -1, "caller_id must be a string", spec.error_value
        args: list[Any] = [self, caller_id]
        try:
            for validator, value in zip(spec.validators, params[1:], strict=False):
                args.append(validator(value, caller_id) if validator else value)
            return fn(*args)
        except Invalid as exc:
            return -1, str(exc), spec.error_value
        except Exception as exc:  # never let one bad call take a server thread down
            log.exception("master: %s failed", method)
            return 0, f"Internal failure: {exc}", spec.error_value

    # notifications ---------------------------------------------------------------------------

    def _notify_params(self, updates: list[ParamUpdate]) -> None:
        for update in updates:
            for _, api in update.subscribers:
                self.notifier.send(api, "paramUpdate", MASTER_CALLER_ID, update.key,
                                   update.value)

    def _notify_topic(self, topic: str) -> None:
        pubs = self.reg.apis(PUBLISHER, topic)
        for api in self.reg.apis(SUBSCRIBER, topic):
            self.notifier.send(api, "publisherUpdate", MASTER_CALLER_ID, topic, pubs)

    def _register(self, kind: str, key: str, caller_id: str, caller_api: str,
                  service_api: str | None = None) -> None:
        bumped = self.reg.register(kind, key, caller_id, caller_api, service_api)
        if bumped is not None:
            log.warning("new node registered with same name: %s (old %s, new %s)",
                        caller_id, bumped, caller_api)
            self.params.unsubscribe_all(caller_id)
            self.notifier.send(bumped, "shutdown", MASTER_CALLER_ID,
                               f"[{caller_id}] Reason: new node registered with same name")

    # master ----------------------------------------------------------------------------------

    @_api(-1)
    def getPid(self, caller_id: str) -> Result:
        return 1, "", os.getpid()

    @_api("")
    def getUri(self, caller_id: str) -> Result:
        return 1, "", self.uri

    @_api(0, None, optional=1)
    def shutdown(self, caller_id: str, msg: str = "") -> Result:
        log.warning("shutdown request from %s: %s", caller_id, msg)
        if self.on_shutdown is not None:
            self.on_shutdown(f"{caller_id}: {msg}")
        return 1, "shutdown", 0

    @_api(0, _graph_name("topic"), _type_name("topic_type"), _is_api("caller_api"))
    def registerPublisher(self, caller_id: str, topic: str, topic_type: str,
                          caller_api: str) -> Result:
        with self._lock:
            self._register(PUBLISHER, topic, caller_id, caller_api)
            if topic_type != ANYTYPE or topic not in self.reg.topic_types:
                self.reg.topic_types[topic] = topic_type
            self._notify_topic(topic)
            subs = self.reg.apis(SUBSCRIBER, topic)
        return 1, f"Registered [{caller_id}] as publisher of [{topic}]", subs

    @_api(0, _graph_name("topic"), _is_api("caller_api"))
    def unregisterPublisher(self, caller_id: str, topic: str, caller_api: str) -> Result:
        with self._lock:
            result = self.reg.unregister(PUBLISHER, topic, caller_id, caller_api)
            if result[2]:
                self._notify_topic(topic)
        return result

    @_api(0, _graph_name("topic"), _type_name("topic_type"), _is_api("caller_api"))
    def registerSubscriber(self, caller_id: str, topic: str, topic_type: str,
                           caller_api: str) -> Result:
        with self._lock:
            self._register(SUBSCRIBER, topic, caller_id, caller_api)
            if topic not in self.reg.topic_types and topic_type != ANYTYPE:
                self.reg.topic_types[topic] = topic_type
            pubs = self.reg.apis(PUBLISHER, topic)
        return 1, f"Subscribed to [{topic}]", pubs

    @_api(0, _graph_name("topic"), _is_api("caller_api"))
    def unregisterSubscriber(self, caller_id: str, topic: str, caller_api: str) -> Result:
        with self._lock:
            return self.reg.unregister(SUBSCRIBER, topic, caller_id, caller_api)

    @_api(0, _graph_name("service"), _is_api("service_api"), _is_api("caller_api"))
    def registerService(self, caller_id: str, service: str, service_api: str,
                        caller_api: str) -> Result:
        with self._lock:
            self._register(SERVICE, service, caller_id, caller_api, service_api)
        return 1, f"Registered [{caller_id}] as provider of [{service}]", 1

    @_api(0, _graph_name("service"), _is_api("service_api"))
    def unregisterService(self, caller_id: str, service: str, service_api: str) -> Result:
        with self._lock:
            return self.reg.unregister(SERVICE, service, caller_id, service_api=service_api)

    @_api("", _graph_name("service"))
    def lookupService(self, caller_id: str, service: str) -> Result:
        url = self.reg.service_api(service)
        if url:
            return 1, f"rosrpc URI: [{url}]", url
        return -1, "no provider", ""

    @_api("", _graph_name("node", allow_root=True))
    def lookupNode(self, caller_id: str, node_name: str) -> Result:
        api = self.reg.node_api(node_name)
        if api is not None:
            return 1, "node api", api
        return -1, f"unknown node [{node_name}]", ""

    @_api(0, _empty_or_name("subgraph"))
    def getPublishedTopics(self, caller_id: str, subgraph: str) -> Result:
        if subgraph and not subgraph.endswith(SEP):
            subgraph += SEP
        with self._lock:
            topics = [[t, self.reg.topic_types.get(t, ANYTYPE)]
                      for t in self.reg.topics[PUBLISHER] if t.startswith(subgraph)]
        return 1, "current topics", topics

    @_api(0)
    def getTopicTypes(self, caller_id: str) -> Result:
        with self._lock:
            types = [[t, ty] for t, ty in self.reg.topic_types.items()]
        return 1, "current system state", types

    @_api(0)
    def getSystemState(self, caller_id: str) -> Result:
        return 1, "current system state", self.reg.system_state()

    # parameter server ------------------------------------------------------------------------

    @_api(0, _non_empty_str("key"))
    def deleteParam(self, caller_id: str, key: str) -> Result:
        key = resolve(key, caller_id)
        with self._lock:
            try:
                self.params.delete(key)  # the tree's listener notifies subscribers
            except KeyError:
                return -1, f"parameter [{key}] is not set", 0
        return 1, f"parameter {key} deleted", 0

    @_api(0, _non_empty_str("key"), _not_none("value"))
    def setParam(self, caller_id: str, key: str, value: Any) -> Result:
        key = resolve(key, caller_id)
        try:
            check_value(key, value)
        except ParamValueError as exc:
            return -1, exc.message, 0
        with self._lock:
            try:
                self.params.set(key, value)  # the tree's listener notifies subscribers
            except TypeError as exc:
                return -1, str(exc), 0
        return 1, f"parameter {key} set", 0

    @_api(0, _non_empty_str("key"))
    def getParam(self, caller_id: str, key: str) -> Result:
        key = resolve(key, caller_id)
        try:
            return 1, f"Parameter [{key}]", self.params.get(key)
        except KeyError:
            return -1, f"Parameter [{key}] is not set", 0

    @_api(0, _non_empty_str("key"))
    def searchParam(self, caller_id: str, key: str) -> Result:
        try:
            found = self.params.search(caller_id, key)
        except ValueError as exc:
            raise Invalid(str(exc)) from None
        if found:
            return 1, f"Found [{found}]", found
        return -1, f"Cannot find parameter [{key}] in an upwards search", ""

    @_api(0, _is_api("caller_api"), _non_empty_str("key"))
    def subscribeParam(self, caller_id: str, caller_api: str, key: str) -> Result:
        key = resolve(key, caller_id)
        with self._lock:
            self._register(PARAM_SUBSCRIBER, subscription_key(key), caller_id, caller_api)
            value = self.params.subscribe(key, caller_id, caller_api)
        return 1, f"Subscribed to parameter [{key}]", value

    @_api(0, _is_api("caller_api"), _non_empty_str("key"))
    def unsubscribeParam(self, caller_id: str, caller_api: str, key: str) -> Result:
        key = resolve(key, caller_id)
        with self._lock:
            self.params.unsubscribe(key, caller_id, caller_api)
            return self.reg.unregister(PARAM_SUBSCRIBER, subscription_key(key), caller_id,
                                       caller_api)

    @_api(False, _non_empty_str("key"))
    def hasParam(self, caller_id: str, key: str) -> Result:
        key = resolve(key, caller_id)
        return 1, key, self.params.has(key)

    @_api([])
    def getParamNames(self, caller_id: str) -> Result:
        return 1, "Parameter names", self.params.names()


# the API's methods by name (one dict lookup a call instead of attribute lookups): every
# function of MasterAPI marked with @_api, and nothing else, is callable over XML-RPC
_METHODS: dict[str, tuple[Callable[..., Result], _Spec]] = {
    name: (fn, fn._api_spec) for name, fn in vars(MasterAPI).items()
    if not name.startswith("_") and isinstance(getattr(fn, "_api_spec", None), _Spec)}
