"""ROS graph names, as a node sees them: pure functions, no state.

A node lives in a namespace (``/ns``) under a full name (``/ns/talker``). Names it uses are
resolved like rospy does it: ``/abs`` stays, ``rel`` goes under the namespace, ``~priv`` goes
under the node's own name, and the result is then looked up in the remapping table (whose
keys and values were resolved the same way when the node started).
"""
from __future__ import annotations

import os
import re
import time
from dataclasses import dataclass, field

SEP = "/"
PRIV = "~"
_VALID = re.compile(r"^[~/]?([A-Za-z][\w]*)?(/[A-Za-z][\w]*)*/?$")
SPECIAL_KEYS = ("__name", "__ns", "__log", "__ip", "__hostname", "__master")


def is_legal_name(name: str) -> bool:
    """Whether ``name`` is a legal ROS graph name (or empty, which means 'the namespace')."""
    return name == "" or bool(_VALID.match(name)) and "//" not in name


def canonical(name: str) -> str:
    """Collapse repeated slashes and drop a trailing one (but keep a lone ``/``)."""
    if not name:
        return name
    parts = [p for p in name.split(SEP) if p]
    text = SEP.join(parts)
    return SEP + text if name.startswith(SEP) else text


def ns_join(namespace: str, name: str) -> str:
    """``name`` inside ``namespace`` (a global or private name is returned unchanged)."""
    if name.startswith((SEP, PRIV)) or not namespace:
        return name
    if namespace.endswith(SEP):
        return namespace + name
    return namespace + SEP + name


def namespace_of(name: str) -> str:
    """The namespace holding the global name ``name`` (``/a/b`` -> ``/a/``, ``/b`` -> ``/``)."""
    name = canonical(name)
    if name in ("", SEP):
        return SEP
    head = name.rsplit(SEP, 1)[0]
    return (head or "") + SEP


def make_global_ns(namespace: str) -> str:
    """A namespace in its ``/ns/`` form."""
    namespace = canonical(namespace or SEP)
    if not namespace.startswith(SEP):
        namespace = SEP + namespace
    return namespace if namespace.endswith(SEP) else namespace + SEP


def resolve(name: str, namespace: str, node_name: str,
            remaps: dict[str, str] | None = None) -> str:
    """The global name ``name`` stands for, in a node called ``node_name`` living in ``namespace``.

    ``remaps`` maps resolved names to resolved names; it is consulted last, once.
    """
    if not name:
        resolved = canonical(make_global_ns(namespace)) or SEP
    elif name.startswith(PRIV):
        resolved = canonical(node_name + SEP + name[1:])
    elif name.startswith(SEP):
        resolved = canonical(name)
    else:
        resolved = canonical(make_global_ns(namespace) + name)
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
        elif src.startswith("_") and not src.startswith("__"):
            params[src[1:]] = dst
        else:
            remaps[src] = dst
    return NodeArgs(remaps, special, params, plain)


def resolve_remaps(raw: dict[str, str], namespace: str, node_name: str) -> dict[str, str]:
    """Remap table with both sides resolved in the node's scope, as rospy does at start."""
    table: dict[str, str] = {}
    for src, dst in raw.items():
        table[resolve(src, namespace, node_name)] = resolve(dst, namespace, node_name)
    return table


def anonymous_name(base: str) -> str:
    """A name unlikely to clash: rospy's ``<base>_<pid>_<millis>`` pattern."""
    return f"{base}_{os.getpid()}_{int(time.time() * 1000)}"
