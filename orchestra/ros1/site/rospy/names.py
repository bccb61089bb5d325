"""rospy.names: this node's names and the resolution rules of orchestra's runtime."""
from __future__ import annotations

from orchestra import names as _graph_names
from orchestra.node.runtime import get_caller_id, get_name, get_namespace, get_runtime, resolve_name

__all__ = ["canonicalize_name", "get_caller_id", "get_mappings", "get_name", "get_namespace",
           "get_resolved_mappings", "remap_name", "resolve_name", "scoped_name"]

canonicalize_name = _graph_names.canonicalize


def remap_name(name: str, caller_id: str | None = None, resolved: bool = True) -> str:
    """``name`` after this node's command-line remappings (rospy.remap_name)."""
    if resolved:
        name = resolve_name(name, caller_id)
    return get_runtime().remaps.get(name, name)


def get_mappings() -> dict[str, str]:
    """The remappings this node was started with, resolved (orchestra keeps only that form)."""
    return dict(get_runtime().remaps)


get_resolved_mappings = get_mappings


def scoped_name(caller_id: str, name: str) -> str:
    """``name`` relative to the namespace of ``caller_id`` (rospy.names.scoped_name)."""
    if not _graph_names.is_global(caller_id):
        raise ValueError("caller_id must be global")
    return _graph_names.canonicalize(name)[len(_graph_names.namespace(caller_id)):]
