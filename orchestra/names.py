"""ROS graph names: joining, canonical forms, legality, private names, anonymous names.

These are the rules every ROS 1 tool shares (rosgraph.names); the launch interpreter, the
master and the node runtime all resolve names here so that a name means the same thing
everywhere. Everything is a small pure function except ``anonymous_name``, which must return
the same value for the same id during one run (roslaunch's ``$(anon x)`` contract).
"""
from __future__ import annotations

import os
import re
import sys

SEP = "/"
GLOBAL_NS = "/"
PRIVATE = "~"
REMAP = ":="

_LEGAL_NAME = re.compile(r"^[~/A-Za-z][\w/]*$")
_LEGAL_BASE_NAME = re.compile(r"^[A-Za-z]\w*$")


def is_global(name: str) -> bool:
    return bool(name) and name[0] == SEP


def is_private(name: str) -> bool:
    return bool(name) and name[0] == PRIVATE


def make_global_ns(name: str) -> str:
    """``name`` as a global namespace with a trailing slash (``a/b`` -> ``/a/b/``)."""
    first = name[:1]  # is_private / is_global, written out: every scope and node asks
    if first == PRIVATE:
        raise ValueError(f"cannot turn [{name}] into a global name")
    if first != SEP:
        name = SEP + name
    if name[-1] != SEP:
        name += SEP
    return name


def ns_join(ns: str, name: str) -> str:
    """Join a namespace and a name; global and private names are left alone."""
    first = name[:1]  # is_private / is_global, written out: every param and key asks
    if first == PRIVATE or first == SEP:
        return name
    if ns == PRIVATE:
        return PRIVATE + name
    if not ns:
        return name
    if ns[-1] == SEP:
        return ns + name
    return ns + SEP + name


def canonicalize(name: str) -> str:
    """Drop empty segments and the trailing slash (``//a//b/`` -> ``/a/b``)."""
    if not name or name == SEP:
        return name
    if name[-1] != SEP and "//" not in name:
        return name  # already canonical: the usual case
    parts = [p for p in name.split(SEP) if p]
    if name[0] == SEP:
        return SEP + SEP.join(parts)
    return SEP.join(parts)


def namespace(name: str) -> str:
    """The namespace holding ``name`` (``/a/b`` -> ``/a/``)."""
    if not name:
        return SEP
    if name[-1] == SEP:
        name = name[:-1]
    return name[: name.rfind(SEP) + 1] or SEP


def is_legal_name(name: str | None) -> bool:
    """True for a valid (possibly relative, private or global) graph name; '' is legal."""
    if name is None:
        return False
    if name == "":
        return True
    return bool(_LEGAL_NAME.fullmatch(name)) and "//" not in name


def is_legal_base_name(name: str | None) -> bool:
    """True for a single name segment (a node's base name)."""
    return name is not None and bool(_LEGAL_BASE_NAME.fullmatch(name))


def resolve_name(name: str, ns: str = GLOBAL_NS, node_name: str | None = None) -> str:
    """Resolve ``name`` against namespace ``ns``; ``~x`` resolves under ``node_name``."""
    if not name:
        return canonicalize(make_global_ns(ns)) or SEP
    if is_private(name):
        if node_name is None:
            raise ValueError(f"private name [{name}] needs a node name")
        return canonicalize(ns_join(make_global_ns(node_name), name[1:]))
    if is_global(name):
        return canonicalize(name)
    return canonicalize(ns_join(make_global_ns(ns), name))


def _host_token() -> str:
    import socket  # here: the CLI's start-up path imports this module, rarely an $(anon)

    return socket.gethostname()


_ANON: dict[str, str] = {}


def anonymous_name(anon_id: str) -> str:
    """``<id>_<host>_<pid>_<random>``, the same value for the same id in this process.

    Like roslaunch, ``.``, ``-`` and ``:`` become ``_`` in the whole result so the name stays
    a legal graph name whatever the host is called.
    """
    cached = _ANON.get(anon_id)
    if cached is None:
        import random  # only anon names need it (~1 ms of every short process otherwise)

        raw = f"{anon_id}_{_host_token()}_{os.getpid()}_{random.randint(0, sys.maxsize)}"
        cached = raw.replace(".", "_").replace("-", "_").replace(":", "_")
        _ANON[anon_id] = cached
    return cached


def load_mappings(argv: list[str]) -> dict[str, str]:
    """``name:=value`` words of a command line, as roslaunch reads launch arguments.

    Only words whose name starts with a letter, ``~``, ``/`` or ``_`` count (roslaunch
    silently drops ``3d_sensor:=kinect``); ``_x:=v`` is a private-parameter assignment, not
    a mapping; a word with more than one ``:=`` is ignored.
    """
    mappings: dict[str, str] = {}
    for word in argv:
        if REMAP not in word:
            continue
        parts = [p.strip() for p in word.split(REMAP)]
        if len(parts) != 2:
            continue
        src, dst = parts
        if not src or not dst:
            continue
        if not (src[0].isascii() and (src[0].isalpha() or src[0] in "~/_")):
            continue
        if len(src) > 1 and src[0] == "_" and src[1] != "_":
            continue
        mappings[src] = dst
    return mappings
