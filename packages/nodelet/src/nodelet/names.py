"""ROS graph-name rules a nodelet needs for itself (pure functions).

A nodelet lives inside another process (its manager), so the process-wide name resolution
of ``orchestra.node`` (which knows only the manager's name and remaps) is the wrong one:
each nodelet resolves its names against ITS OWN name, namespace and remappings, which the
loader hands over. Same rules as roscpp: ``/x`` global, ``~x`` private, ``x`` relative to
the namespace; remappings are matched on the resolved name.
"""
from __future__ import annotations


class NameError_(ValueError):
    """A graph name that ROS would reject."""


def canonicalize(name: str) -> str:
    """Collapse repeated slashes and drop a trailing one (the root stays ``/``)."""
    if not name:
        return name
    parts = [p for p in name.split("/") if p]
    prefix = "/" if name.startswith("/") else ""
    return prefix + "/".join(parts) if parts else "/"


def namespace_of(name: str) -> str:
    """The namespace holding the global name ``name`` (``/a/b`` -> ``/a``, ``/a`` -> ``/``)."""
    name = canonicalize(name)
    head = name.rsplit("/", 1)[0]
    return head or "/"


def join(namespace: str, name: str) -> str:
    return canonicalize(f"{namespace}/{name}")


def resolve(name: str, node_name: str, remaps: dict[str, str] | None = None) -> str:
    """The global name of ``name`` as seen by the node ``node_name`` (a global name)."""
    if not name:
        resolved = namespace_of(node_name)
    elif name.startswith("/"):
        resolved = canonicalize(name)
    elif name.startswith("~"):
        resolved = join(node_name, name[1:])
    else:
        resolved = join(namespace_of(node_name), name)
    if remaps:
        resolved = remaps.get(resolved, resolved)
    return resolved


def is_remap_arg(arg: str) -> bool:
    """``from:=to`` words that remap names (not ``_param:=`` nor ``__special:=``)."""
    if ":=" not in arg:
        return False
    return not arg.startswith("_")


def parse_remaps(argv: list[str], node_name: str) -> dict[str, str]:
    """Resolved ``{from: to}`` for the remap words of ``argv``, as the node ``node_name``
    sees them (both sides resolved in its namespace, ``~`` against its name)."""
    remaps: dict[str, str] = {}
    for arg in argv:
        if not is_remap_arg(arg):
            continue
        src, dst = arg.split(":=", 1)
        if not src or not dst:
            continue
        remaps[resolve(src, node_name)] = resolve(dst, node_name)
    return remaps


def strip_ros_args(argv: list[str]) -> list[str]:
    """``argv`` without any ``a:=b`` word (what rospy's ``myargv`` returns)."""
    return [a for a in argv if ":=" not in a]
