"""The core node roscore brings: ``/rosout``, started wherever orchestra serves the master.

roscore (and roslaunch when it starts its own core) runs roscore.xml, whose only node is
``<node pkg="rosout" type="rosout" name="rosout" respawn="true"/>``: it aggregates every
node's log messages on ``/rosout_agg`` (what rqt_console shows) and in ``rosout.log``. So:

- ``orchestra launch`` with the embedded master starts it first (process counter 1, so its
  files are ``rosout-1-*.log`` and the plan's nodes count from 2, as with roslaunch);
- ``orchestra core`` supervises it as its only child;
- with an external master nothing is added: whoever started that master owns its rosout.

``--no-rosout`` turns it off in both. A plan that declares its own ``/rosout`` keeps it (ours
is not added), and when no ``rosout`` package can be found the run goes on without it after a
warning: a missing log aggregator is no reason to refuse to start a robot.
"""
from __future__ import annotations

import logging
import os
import threading
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING

from orchestra.errors import OrchestraError
from orchestra.launch.plan import Node

if TYPE_CHECKING:
    from orchestra.supervise.supervisor import RunResult

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
    from orchestra.supervise.command import find_node_executable

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


def serve_core(handle, run_id: str, rosout: bool, watchdog, echo: Callable[[str], None],
               announce: Callable[[], None] | None = None) -> RunResult:
    """``orchestra core`` after its master is up: supervise the core nodes until a signal or
    the master's own ``shutdown``; the result's exit code is 1 when a core node ended FAILED.

    The supervisor's loop owns SIGINT/SIGTERM/SIGHUP, so a Ctrl-C stops /rosout first (it
    still unregisters from the live master), then the caller stops the master. ``announce``
    runs once those signals are handled, before /rosout is spawned.
    """
    from orchestra.supervise.output import prepare_run_log_dir
    from orchestra.supervise.runner import RunOptions, run_specs
    from orchestra.supervise.supervisor import Supervisor

    nodes = core_nodes((), embedded_master=True, enabled=rosout)
    executables = resolve_core_executables(nodes, echo)
    nodes = [node for node in nodes if node.full_name in executables]
    run_dir = prepare_run_log_dir(run_id) if nodes else None
    specs = run_specs(nodes, [], executables, handle.uri, run_dir, RunOptions()) if nodes else []
    supervisor = Supervisor(specs, log_dir=run_dir, watchdog=watchdog, keep_alive=True)

    def stop_with_master() -> None:
        handle.wait()
        supervisor.loop.call_threadsafe(
            lambda: supervisor.request_stop(f"master stopped ({handle.shutdown_reason})"))

    threading.Thread(target=stop_with_master, name="core: master watch", daemon=True).start()

    def before_start() -> None:
        if announce is not None:
            announce()
        if run_dir is not None:
            echo(f"logging to {run_dir}")

    result = supervisor.run(before_start=before_start)
    if result.failed:
        echo(f"orchestra: error: {result.reason}")
    return result
