"""``orchestra check --check-machines``: can every remote machine of a launch run its nodes?

The same preflight ``orchestra launch`` does before starting anything (RemoteSession.open:
connect, run the env-loader and the agent, find every node's executable there), one machine
at a time, each closed again at once. A machine that fails is a finding, not an exception, so
one run lists every unreachable or misconfigured machine.
"""
from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass

from orchestra.errors import Location, OrchestraError
from orchestra.launch.plan import LaunchPlan, Node
from orchestra.remote.locality import UnresolvableAddress, is_local_machine
from orchestra.remote.session import RemoteSession


@dataclass(frozen=True)
class MachineProblem:
    location: Location | None
    message: str


def _where(node: Node) -> Location | None:
    return Location(node.filename, node.line) if node.filename else None


def remote_nodes_by_machine(plan: LaunchPlan) -> tuple[dict[str, list[Node]],
                                                       list[MachineProblem]]:
    """The plan's remote nodes per machine name (roslaunch's locality rule), and the
    machines whose address does not resolve."""
    found: dict[str, list[Node]] = {}
    problems: list[MachineProblem] = []
    verdicts: dict[str, bool] = {}
    for node in (*plan.nodes, *plan.tests):
        machine = plan.machines.get(node.machine_name or "")
        if machine is None or not node.machine_name:
            continue
        if machine.name not in verdicts:
            try:
                verdicts[machine.name] = is_local_machine(machine.address, machine.user)
            except UnresolvableAddress:
                verdicts[machine.name] = True       # nothing to connect to: reported here
                problems.append(MachineProblem(
                    _where(node), f"cannot resolve host address for machine "
                                  f"'{machine.name}' ({machine.address})"))
        if not verdicts[machine.name]:
            found.setdefault(machine.name, []).append(node)
    return found, problems


def check_machines(plans: Iterable[LaunchPlan]) -> list[MachineProblem]:
    """Every remote machine of ``plans`` that cannot run its nodes, with ssh's or its reason."""
    problems: list[MachineProblem] = []
    seen: set[tuple[str, str]] = set()
    for plan in plans:
        by_machine, unresolved = remote_nodes_by_machine(plan)
        problems += unresolved
        for name, nodes in by_machine.items():
            key = (name, plan.machines[name].address)
            if key in seen:
                continue
            seen.add(key)
            try:
                session = RemoteSession(dict(plan.machines), nodes)
                session.open()
                session.close(reap=False)
            except OrchestraError as exc:
                problems.append(MachineProblem(exc.location, exc.message))
    return problems
