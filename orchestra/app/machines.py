"""Which of a plan's nodes run on this machine, and the ssh session for the others.

roslaunch starts the nodes of a remote ``<machine>`` over ssh; so does orchestra
(``orchestra/remote/``). ``--local`` (roslaunch's "do not launch remote nodes") leaves them
out. Every machine is connected and checked before anything starts (all-or-nothing).
"""
from __future__ import annotations

import urllib.parse
from collections.abc import Sequence
from dataclasses import replace
from typing import TYPE_CHECKING, Any

from orchestra.errors import OrchestraError
from orchestra.launch.plan import LaunchPlan, Node
from orchestra.rosdirs import ros_home
from orchestra.supervise.process import ProcessSpec
from orchestra.supervise.reaper import Watchdog
from orchestra.supervise.specs import SpecOptions, build_specs, node_location

if TYPE_CHECKING:
    from orchestra.remote.session import RemoteSession

# orchestra/remote/ (ssh sessions, the agent, interface addresses) is imported only by a
# plan that names a <machine>: a local launch does not pay its import before its nodes start


def split_remote(plan: LaunchPlan, nodes: Sequence[Node]) -> tuple[list[Node], list[Node]]:
    """(nodes to run here, nodes of remote machines), split as roslaunch splits them."""
    here: list[Node] = []
    remote: list[Node] = []
    verdicts: dict[str, bool] = {}
    for node in nodes:
        machine = plan.machines.get(node.machine_name or "")
        if machine is None or not node.machine_name:
            here.append(node)
            continue
        if machine.name not in verdicts:
            from orchestra.remote.locality import UnresolvableAddress, is_local_machine

            try:
                verdicts[machine.name] = is_local_machine(machine.address, machine.user)
            except UnresolvableAddress:
                raise OrchestraError(f"cannot resolve host address for machine "
                                     f"'{machine.name}' ({machine.address})",
                                     node_location(node)) from None
        (here if verdicts[machine.name] else remote).append(node)
    return here, remote


def open_remote(plan: LaunchPlan, remote: list[Node], watchdog: Watchdog) -> RemoteSession:
    """Connect and check every remote machine of the run (orchestra/remote/session.py)."""
    from orchestra.remote.session import RemoteSession

    session = RemoteSession(dict(plan.machines), remote, mark=watchdog.mark,
                            watch=watchdog.watch)
    session.open()
    return session


def master_warnings(master_uri: str, embedded: bool) -> list[str]:
    """A master other machines probably cannot reach: an external one on a loopback URI
    (ours listens on every interface when the plan has remote nodes)."""
    host = urllib.parse.urlsplit(master_uri).hostname or "localhost"
    if embedded or not (host in ("localhost", "::1") or host.startswith("127.")):
        return []
    return [f"orchestra: warning: the master at {master_uri} is external and named by a "
            "loopback address; remote nodes are told to use this host's address instead, "
            "which works only if that master listens on it (set ROS_MASTER_URI to a name "
            "the other machines can reach)"]


def remote_specs(session: Any, remote: list[Node], master_uri: str, run_id: str,
                 run_dir: str | None, options: SpecOptions) -> list[ProcessSpec]:
    """Remote nodes' specs: their run settings as local nodes', their command an ssh session."""
    specs = build_specs(remote, {n.full_name: n.type for n in remote}, master_uri, run_dir,
                        options)
    return [replace(spec, cwd=ros_home(), argv=tuple(session.node_argv(
        node, master_uri, run_id, spec.log_name or node.name, spec.sigint_timeout,
        spec.sigterm_timeout))) for node, spec in zip(remote, specs, strict=True)]
