"""rosgraph.rosenv: the ROS environment variables a node reads."""
from __future__ import annotations

import sys
from collections.abc import Mapping

from orchestra.node.names import parse_args
from orchestra.rpc import master_uri_from_env

__all__ = ["ROS_MASTER_URI", "ROS_NAMESPACE", "get_master_uri"]

ROS_MASTER_URI = "ROS_MASTER_URI"
ROS_NAMESPACE = "ROS_NAMESPACE"


def get_master_uri(env: Mapping[str, str] | None = None, argv: list[str] | None = None) -> str:
    """``__master:=`` from ``argv`` (default ``sys.argv``), else ``ROS_MASTER_URI``, else
    the default master (rosgraph raises instead; orchestra's nodes use the default)."""
    special = parse_args(list(sys.argv if argv is None else argv)).special
    return special.get("__master") or master_uri_from_env(env)
