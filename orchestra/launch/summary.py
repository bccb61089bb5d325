"""roslaunch's SUMMARY block, from a plan: what is about to run, before it runs.

roslaunch prints it at every start (unless ``--no-summary``), and users read it to check the
parameters and node names a launch file resolved to. The layout is roslaunch's: sorted
``CLEAR PARAMETERS``, ``PARAMETERS`` with values cut to 20 characters, ``MACHINES`` only when
remote nodes are part of the run, and ``NODES`` grouped by namespace, sorted. roslaunch's
parameters include roscore's (``/rosdistro``, ``/rosversion``), which it always loads: the
caller passes them as ``core_params``, since the plan holds only the launch file's.
"""
from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from orchestra.launch.plan import LaunchPlan, Node

MAX_VALUE = 20


def summary_value(value: Any) -> str:
    """A parameter value as roslaunch shows it: ``str()``, cut to 20, ``<...>`` if unprintable."""
    text = str(value)
    if len(text) > MAX_VALUE:
        text = text[:MAX_VALUE - 3] + "..."
    stripped = text.rstrip()
    for i, char in enumerate(text):
        if not 32 <= ord(char) <= 126:
            # unprintable only in trailing whitespace is fine: it is dropped
            return stripped if i >= len(stripped) else "<...>"
    return text


def node_label(node: Node) -> str:
    return f"{node.name} ({node.package}/{node.type})" if node.name \
        else f"{node.package}/{node.type}"


def summary(plan: LaunchPlan, core_params: Mapping[str, Any] | None = None,
            nodes: list[Node] | None = None, remote: bool = False) -> str:
    """The SUMMARY text roslaunch prints for ``plan`` (``nodes``: those run, default all)."""
    text = "\nSUMMARY\n========"
    if plan.clear_params:
        text += "\n\nCLEAR PARAMETERS\n" + "\n".join(sorted(f" * {p}" for p in plan.clear_params))
    params = {**(core_params or {}), **plan.params}
    if params:
        text += "\n\nPARAMETERS\n" + "\n".join(
            sorted(f" * {k}: {summary_value(v)}" for k, v in params.items()))
    if remote:
        text += "\n\nMACHINES\n" + "\n".join(sorted(f" * {k}" for k in plan.machines if k))
    text += "\n\nNODES\n"
    by_ns: dict[str, list[Node]] = {}
    for node in plan.nodes if nodes is None else nodes:
        by_ns.setdefault(node.namespace, []).append(node)
    for ns in sorted(by_ns):
        text += f"  {ns}\n" + "\n".join(sorted(f"    {node_label(n)}" for n in by_ns[ns]))
        text += "\n"
    return text
