"""rospy.msproxy.MasterProxy: the master's XML-RPC API as this node (``rospy.get_master()``).

Attribute calls send this node's caller id first and return the raw ``[code, msg, value]``
triple, as rospy's proxy does; item access is the parameter server with Python semantics."""
from __future__ import annotations

from collections.abc import Callable, Iterator
from typing import Any

from orchestra.node import runtime
from orchestra.node.exceptions import ROSException
from orchestra.node.masterapi import raw_call

__all__ = ["MasterProxy"]

#: arguments (after the caller id) that are graph names, resolved in the node's namespace
_NAME_ARGS = {"getParam": (0,), "setParam": (0,), "deleteParam": (0,), "hasParam": (0,),
              "subscribeParam": (1,), "unsubscribeParam": (1,), "registerService": (0,),
              "unregisterService": (0,), "lookupService": (0,), "registerSubscriber": (0,),
              "unregisterSubscriber": (0,), "registerPublisher": (0,),
              "unregisterPublisher": (0,), "lookupNode": (0,), "getPublishedTopics": (0,)}


class MasterProxy:
    def __init__(self, uri: str):
        self.uri = uri

    def _caller(self) -> str:
        return runtime.get_caller_id() if runtime.is_initialized() else "/unnamed"

    def _resolve(self, name: str) -> str:
        return runtime.resolve_name(name) if runtime.is_initialized() else name

    def __getattr__(self, method: str) -> Callable[..., list]:
        if method.startswith("_"):
            raise AttributeError(method)

        def call(*args: Any) -> list:
            args_l = list(args)
            for i in _NAME_ARGS.get(method, ()):
                if i < len(args_l):
                    args_l[i] = self._resolve(args_l[i])
            return raw_call(self.uri, method, self._caller(), *args_l)
        return call

    def __getitem__(self, key: str) -> Any:
        code, _, value = raw_call(self.uri, "getParam", self._caller(), self._resolve(key))
        if code != 1:
            raise KeyError(key)
        return value

    def __setitem__(self, key: str, value: Any) -> None:
        raw_call(self.uri, "setParam", self._caller(), self._resolve(key), value)

    def __delitem__(self, key: str) -> None:
        code, msg, _ = raw_call(self.uri, "deleteParam", self._caller(), self._resolve(key))
        if code == -1:
            raise KeyError(key)
        if code != 1:
            raise ROSException(f"cannot delete parameter: {msg}")

    def __contains__(self, key: str) -> bool:
        code, msg, value = raw_call(self.uri, "hasParam", self._caller(), self._resolve(key))
        if code != 1:
            raise ROSException(f"cannot check parameter on server: {msg}")
        return bool(value)

    def __iter__(self) -> Iterator[str]:
        code, msg, value = raw_call(self.uri, "getParamNames", self._caller())
        if code != 1:
            raise ROSException(f"cannot retrieve parameter names: {msg}")
        return iter(value)

    def search_param(self, key: str) -> str | None:
        code, msg, value = raw_call(self.uri, "searchParam", self._caller(), key)
        if code == 1:
            return value
        if code == -1:
            return None
        raise ROSException(f"cannot search for parameter: {msg}")

    def get_param_cached(self, key: str) -> Any:
        return self[key]
