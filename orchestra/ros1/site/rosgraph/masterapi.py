"""rosgraph.masterapi: ``Master(caller_id)`` whose methods are the master's XML-RPC API with
the caller id filled in and the ``[code, msg, value]`` reply unwrapped: the value, or
``MasterFailure`` (code 0) / ``MasterError`` (code -1), as rosgraph does."""
from __future__ import annotations

from collections.abc import Callable
from typing import Any

from orchestra.node.masterapi import MasterError as _Unreachable
from orchestra.node.masterapi import raw_call

from .rosenv import get_master_uri

__all__ = ["Master", "MasterError", "MasterException", "MasterFailure", "is_online"]


class MasterException(Exception):
    """Base of the master's error replies."""


class MasterFailure(MasterException):
    """The master answered with code 0 (failure)."""


class MasterError(MasterException):
    """The master answered with code -1 (error)."""


class Master:
    def __init__(self, caller_id: str, master_uri: str | None = None):
        if master_uri is None:
            master_uri = get_master_uri()
        self.caller_id = caller_id
        self.master_uri = master_uri

    def __getattr__(self, method: str) -> Callable[..., Any]:
        if method.startswith("_"):
            raise AttributeError(method)

        def call(*args: Any) -> Any:
            code, msg, value = raw_call(self.master_uri, method, self.caller_id, *args)
            if code == 1:
                return value
            if code == 0:
                raise MasterFailure(code, msg, value)
            raise MasterError(code, msg, value)
        return call

    def is_online(self) -> bool:
        try:
            self.getPid()
            return True
        except (MasterException, _Unreachable):
            return False


def is_online(master_uri: str | None = None) -> bool:
    return Master("/rosgraph", master_uri).is_online()
