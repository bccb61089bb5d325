"""rosgraph.names: ROS graph name rules, orchestra's (orchestra/names.py)."""
from __future__ import annotations

import os
import sys
from collections.abc import Mapping

from orchestra.names import anonymous_name as _anonymous_name
from orchestra.names import (
    canonicalize,
    is_global,
    is_legal_base_name,
    is_legal_name,
    is_private,
    load_mappings,
    make_global_ns,
    namespace,
    ns_join,
)
from orchestra.names import resolve_name as _resolve
from orchestra.node.names import parse_args

__all__ = ["ANYTYPE", "PRIV_NAME", "SEP", "anonymous_name", "canonicalize_name",
           "get_ros_namespace", "is_global", "is_legal_base_name", "is_legal_name",
           "is_private", "load_mappings", "make_caller_id", "make_global_ns", "namespace",
           "ns_join", "resolve_name", "script_resolve_name"]

SEP = "/"
PRIV_NAME = "~"
ANYTYPE = "*"
canonicalize_name = canonicalize


def anonymous_name(id: str) -> str:  # noqa: A002 - rosgraph's parameter name
    """A node name made unique with the host, pid and a random part."""
    return _anonymous_name(id)


def get_ros_namespace(env: Mapping[str, str] | None = None,
                      argv: list[str] | None = None) -> str:
    """``__ns:=`` from ``argv``, else ``ROS_NAMESPACE``, as a global namespace."""
    special = parse_args(list(sys.argv if argv is None else argv)).special
    env = os.environ if env is None else env
    return make_global_ns(special.get("__ns") or env.get("ROS_NAMESPACE") or SEP)


def make_caller_id(name: str) -> str:
    """``name`` resolved in this process's namespace (a node name)."""
    return make_global_ns(ns_join(get_ros_namespace(), name))[:-1]


def resolve_name(name: str, namespace_: str, remappings: Mapping[str, str] | None = None) -> str:
    """``name`` resolved in ``namespace_`` (``~`` names against it, as a node name), then
    looked up in ``remappings``."""
    if is_private(name):
        resolved = _resolve(name, namespace(namespace_), namespace_)
    else:
        resolved = _resolve(name, namespace_)
    return (remappings or {}).get(resolved, resolved)


def script_resolve_name(script_name: str, name: str) -> str:
    """How a command-line tool named ``script_name`` resolves ``name`` (ROS_NAMESPACE)."""
    if not name:
        return get_ros_namespace()
    if is_global(name):
        return name
    if is_private(name):
        return ns_join(make_caller_id(script_name), name[1:])
    return get_ros_namespace() + name
