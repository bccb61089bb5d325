"""The core node roscore brings: ``/rosout``, started wherever orchestra serves the master.

roscore (and roslaunch when it starts its own core) runs roscore.xml, whose only node is
``<node pkg="rosout" type="rosout" name="rosout" respawn="true"/>``: it aggregates every
node's log messages on ``/rosout_agg`` (what rqt_console shows) and in ``rosout.log``. So:

- ``orchestra launch`` with the embedded master starts it first (process counter 1, so its
  files are ``rosout-1-*.log`` and the plan's nodes count from 2, as with roslaunch);
- ``orchestra core`` supervises it as its only child (``app/core.py``);
- with an external master nothing is added: whoever started that master owns its rosout.

``--no-rosout`` turns it off in both. A plan that declares its own ``/rosout`` keeps it (ours
is not added), and when no ``rosout`` package can be found the run goes on without it after a
warning: a missing log aggregator is no reason to refuse to start a robot.
"""
from __future__ import annotations

import logging
import os
from collections.abc import Callable, Sequence

from orchestra.errors import OrchestraError
from orchestra.launch.plan import Node
from orchestra.supervise.command import find_node_executable

logger = logging.getLogger(__name__)

ROSOUT = Node(package="rosout", type="rosout", name="rosout", namespace="/", respawn=True)


def core_nodes(nodes: Sequence[Node], embedded_master: bool, enabled: bool = True) -> list[Node]:
    """The roscore.xml nodes to start before ``nodes``: /rosout when we serve the master."""
    if not embedded_master or not enabled:
        return []
    if any(node.full_name == ROSOUT.full_name for node in nodes):
        return []
    return [ROSOUT]


def resolve_core_executables(nodes: Sequence[Node], warn: Callable[[str], None]
                             ) -> dict[str, str]:
    """Full name -> executable of the core nodes that can be found; the others are warned
    about and left out (see module docstring)."""
    found: dict[str, str] = {}
    for node in nodes:
        try:
            found[node.full_name] = find_node_executable(node)
        except OrchestraError as exc:
            warn(f"orchestra: warning: not starting {node.full_name}: {exc.message}")
    return found


def releases_sigint(executable: str) -> bool:
    """Whether ``executable`` is orchestra's own rosout, which unblocks SIGINT itself once its
    handlers are installed (so it may be started with SIGINT held: see ``ProcessSpec``). A
    rosout found elsewhere (a real ROS install) is started like any node."""
    from orchestra.packages.index import BUNDLED_PACKAGES

    bundled = os.path.realpath(os.path.join(BUNDLED_PACKAGES, ROSOUT.package)) + os.sep
    return os.path.realpath(executable).startswith(bundled)
