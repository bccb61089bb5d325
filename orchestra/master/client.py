"""Talking to a master (ours or a real rosmaster) from tools: find it, probe it, upload.

Everything here speaks plain XML-RPC, so the same code drives an orchestra master, an
embedded one, or ROS's own rosmaster.
"""
from __future__ import annotations

import urllib.parse
import xmlrpc.client
from collections.abc import Mapping, Sequence
from typing import Any

from orchestra.errors import OrchestraError
from orchestra.params.tree import check_value
from orchestra.rpc import (
    DEFAULT_MASTER_URI,
    DEFAULT_PORT,
    TRANSPORT_ERRORS,
    MasterUnreachable,
    master_is_up,
    master_uri_from_env,
    multicall_results,
    proxy,
)

__all__ = [
    "DEFAULT_MASTER_URI", "DEFAULT_PORT", "TRANSPORT_ERRORS", "MasterUnreachable",
    "master_is_up", "master_uri_from_env", "port_from_uri", "proxy", "upload_params",
]


def port_from_uri(uri: str) -> int:
    """The TCP port of a master URI (11311 when the URI names none)."""
    try:
        port = urllib.parse.urlsplit(uri).port
    except ValueError:
        raise OrchestraError(f"invalid master URI '{uri}' (expected http://host:port/)") from None
    return port if port is not None else DEFAULT_PORT


def upload_params(master_uri: str, params: Mapping[str, Any], clear_params: Sequence[str],
                  caller_id: str = "/roslaunch") -> None:
    """Clear ``clear_params`` namespaces then set every param, in ONE system.multicall.

    Values are checked first, so a value XML-RPC cannot carry fails before anything is sent
    (nothing half-uploaded). Deleting a namespace that is not set answers -1, which is fine:
    roslaunch's clear_params means "make sure it is empty".
    """
    for name, value in params.items():
        check_value(name, value)
    names = list(params)
    try:
        with proxy(master_uri, timeout=30.0) as server:
            multi = xmlrpc.client.MultiCall(server)
            for ns in clear_params:
                multi.deleteParam(caller_id, ns)
            for name in names:
                multi.setParam(caller_id, name, params[name])
            results = multicall_results(multi)
    except xmlrpc.client.Fault as exc:
        raise OrchestraError(f"master at {master_uri} refused the parameters: "
                             f"{exc.faultString}") from None
    except TRANSPORT_ERRORS as exc:
        raise MasterUnreachable(f"cannot reach the master at {master_uri}: {exc}") from None
    for name, (code, message, _) in zip(names, results[len(clear_params):], strict=False):
        if code != 1:
            raise OrchestraError(f"master refused parameter '{name}': {message}")
