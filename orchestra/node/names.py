"""Graph names as a node sees them: the shared rules of ``orchestra.names`` plus what only a
node needs — splitting its command line, resolving its remap table, rospy's anonymous names.

A node lives in a namespace (``/ns/``) under a full name (``/ns/talker``). Names it uses are
resolved like rospy does it: ``/abs`` stays, ``rel`` goes under the namespace, ``~priv`` goes
under the node's own name, and the result is then looked up in the remapping table (whose
keys and values were resolved the same way when the node started).
"""
from __future__ import annotations

import os
import time
from dataclasses import dataclass, field

from orchestra.names import canonicalize as canonical
from orchestra.names import is_legal_name, make_global_ns, resolve_name
from orchestra.names import namespace as namespace_of

__all__ = ["NodeArgs", "anonymous_name", "canonical", "is_legal_name", "is_remap_arg",
           "make_global_ns", "namespace_of", "parse_args", "resolve", "resolve_remaps"]


def resolve(name: str, namespace: str, node_name: str,
            remaps: dict[str, str] | None = None) -> str:
    """The global name ``name`` stands for, in a node called ``node_name`` living in ``namespace``.

    ``remaps`` maps resolved names to resolved names; it is consulted last, once.
    """
    resolved = resolve_name(name, namespace or "/", node_name)
    if remaps and resolved in remaps:
        return remaps[resolved]
    return resolved


@dataclass(frozen=True)
class NodeArgs:
    """What a node's command line says about the node itself."""

    remaps: dict[str, str] = field(default_factory=dict)       # raw 'from' -> 'to' text
    special: dict[str, str] = field(default_factory=dict)      # __name, __ns, __master, ...
    private_params: dict[str, str] = field(default_factory=dict)  # '_x' -> yaml text
    argv: list[str] = field(default_factory=list)              # everything else


def is_remap_arg(arg: str) -> bool:
    """Whether a command-line word is a ROS ``from:=to`` argument (stripped by ``myargv``)."""
    return ":=" in arg and not arg.startswith(":=")


def parse_args(argv: list[str]) -> NodeArgs:
    """Split a command line into plain arguments, remaps, special keys and private params."""
    remaps: dict[str, str] = {}
    special: dict[str, str] = {}
    params: dict[str, str] = {}
    plain: list[str] = []
    for arg in argv:
        if not is_remap_arg(arg):
            plain.append(arg)
            continue
        src, dst = arg.split(":=", 1)
        if src.startswith("__"):
            special[src] = dst
        elif src.startswith("_"):
            params[src[1:]] = dst
        else:
            remaps[src] = dst
    return NodeArgs(remaps, special, params, plain)


def resolve_remaps(raw: dict[str, str], namespace: str, node_name: str) -> dict[str, str]:
    """Remap table with both sides resolved in the node's scope, as rospy does at start."""
    return {resolve(src, namespace, node_name): resolve(dst, namespace, node_name)
            for src, dst in raw.items()}


def anonymous_name(base: str) -> str:
    """rospy's anonymous node name, ``<base>_<pid>_<millis>`` (roslaunch's ``$(anon)`` form
    lives in ``orchestra.names``)."""
    return f"{base}_{os.getpid()}_{int(time.time() * 1000)}"
