"""XML-RPC clients for the ROS Master and for other nodes' slave APIs.

Every ROS XML-RPC call answers ``[code, statusMessage, value]``: 1 success, 0 failure, -1
error. ``call`` unwraps that. Calls go over kept connections (``rpc.pooled_call``: one
proxy per call at a time, as xmlrpc.client's proxies are not thread-safe), since opening a
connection per call costs several times the call itself.
"""
from __future__ import annotations

import xmlrpc.client
from typing import Any

from orchestra import rpc
from orchestra.node.exceptions import ROSException
from orchestra.rpc import TRANSPORT_ERRORS

DEFAULT_TIMEOUT = 10.0


class MasterError(ROSException):
    """The master (or a node's slave API) answered with a failure code, or was unreachable."""

    def __init__(self, message: str, code: int | None = None):
        super().__init__(message)
        self.code = code


def raw_call(uri: str, method: str, *args: Any, timeout: float = DEFAULT_TIMEOUT) -> list:
    """``[code, msg, value]`` from ``method`` at ``uri``; unreachable -> MasterError."""
    try:
        result = rpc.pooled_call(uri, method, *args, timeout=timeout)
    except TRANSPORT_ERRORS as exc:
        raise MasterError(f"cannot reach {uri} ({method}): {exc}") from exc
    except xmlrpc.client.Fault as exc:
        raise MasterError(f"{uri} {method} failed: {exc.faultString}") from exc
    if not isinstance(result, (list, tuple)) or len(result) != 3:
        raise MasterError(f"{uri} {method}: malformed reply {result!r}")
    return list(result)


def call(uri: str, method: str, *args: Any, timeout: float = DEFAULT_TIMEOUT) -> Any:
    """The value of a successful call; a failure code raises ``MasterError``."""
    code, msg, value = raw_call(uri, method, *args, timeout=timeout)
    if code != 1:
        raise MasterError(f"{method}: {msg}", code)
    return value


class Master:
    """The ROS Master API as seen by one caller."""

    def __init__(self, uri: str, caller_id: str):
        self.uri = uri
        self.caller_id = caller_id

    def call(self, method: str, *args: Any) -> Any:
        return call(self.uri, method, self.caller_id, *args)

    def raw(self, method: str, *args: Any) -> list:
        return raw_call(self.uri, method, self.caller_id, *args)

    def is_online(self) -> bool:
        try:
            self.call("getPid")
            return True
        except MasterError:
            return False
