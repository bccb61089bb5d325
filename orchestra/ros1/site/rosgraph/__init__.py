"""rosgraph for orchestra's ROS 1 layer: graph names (``rosgraph.names``), the master API
(``rosgraph.Master``, ``rosgraph.masterapi``) and the environment helpers nodes use."""
from __future__ import annotations

import sys

from orchestra.node.names import is_remap_arg

from .masterapi import Master, MasterError, MasterException, MasterFailure, is_online
from .rosenv import ROS_MASTER_URI, get_master_uri

__all__ = ["Master", "MasterError", "MasterException", "MasterFailure", "ROS_MASTER_URI",
           "get_master_uri", "is_master_online", "myargv"]


def is_master_online(master_uri: str | None = None) -> bool:
    return is_online(master_uri)


def myargv(argv: list[str] | None = None) -> list[str]:
    """``argv`` (default ``sys.argv``) without the ``name:=value`` remapping words."""
    return [a for a in (sys.argv if argv is None else argv) if not is_remap_arg(a)]
