"""From plan nodes to ProcessSpecs: roslaunch's argv/env/cwd plus orchestra's run settings.

The only place where supervise reads the plan's ``Node``: everything after this works on
ProcessSpecs. What a spec needs from the run's options is ``SpecOptions``; the app layer's
RunOptions extends it with what concerns the master and the user interface.
"""
from __future__ import annotations

import os
import sys
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace

from orchestra.errors import Location, OrchestraError
from orchestra.launch.plan import Node
from orchestra.ros1.activation import layer_env
from orchestra.supervise.command import (
    find_node_executable,
    node_argv,
    node_cwd,
    node_env,
    path_with_interpreter,
)
from orchestra.supervise.process import Limits, OutputMode, ProcessSpec
from orchestra.supervise.rosout import releases_sigint


@dataclass(frozen=True)
class SpecOptions:
    """The run settings that shape each process spec (flags of ``orchestra launch``)."""

    force_screen: bool = False
    force_log: bool = False
    all_required: bool = False
    sigint_timeout: float = ProcessSpec.sigint_timeout
    sigterm_timeout: float = ProcessSpec.sigterm_timeout
    node_timeouts: Mapping[str, tuple[float | None, float | None]] = field(default_factory=dict)


def node_location(node: Node) -> Location | None:
    """Where the node was declared, for error messages."""
    return Location(node.filename, node.line) if node.filename else None


def check_unique_names(nodes: Sequence[Node]) -> None:
    """Two processes with one name cannot be supervised (nor registered on a master)."""
    seen: dict[str, Node] = {}
    for node in nodes:
        first = seen.setdefault(node.full_name, node)
        if first is not node:
            where = f" (first at {node_location(first)})" if first.filename else ""
            raise OrchestraError(f"two nodes are named '{node.full_name}'{where}",
                                 node_location(node))


def resolve_executables(nodes: Sequence[Node]) -> dict[str, str]:
    """Full name -> executable for every node; ALL problems reported before anything starts.

    Each (package, type) is looked up once: the lookup walks the package tree, and a launch
    of many instances of one node type paid that walk per node."""
    found: dict[str, str] = {}
    paths: dict[tuple[str, str], str] = {}
    errors: list[OrchestraError] = []
    for node in nodes:
        key = (node.package, node.type)
        try:
            if key not in paths:
                paths[key] = find_node_executable(node)
            found[node.full_name] = paths[key]
        except OrchestraError as exc:
            errors.append(exc)
    if errors:
        first = errors[0]
        more = f" (and {len(errors) - 1} more node(s) like it)" if len(errors) > 1 else ""
        raise OrchestraError(first.message + more, first.location)
    return found


def log_base_name(full_name: str, counter: int) -> str:
    """roslaunch's per-process name for log files: ``robot1-listener-3``."""
    return f"{full_name.lstrip('/').replace('/', '-')}-{counter}"


def output_mode(node: Node, options: SpecOptions) -> OutputMode:
    if options.force_screen:
        return OutputMode.SCREEN
    if options.force_log:
        return OutputMode.LOG
    if node.output == "screen":
        return OutputMode.SCREEN
    if node.output == "both":
        return OutputMode.BOTH
    return OutputMode.LOG


def build_specs(nodes: Sequence[Node], executables: Mapping[str, str], master_uri: str,
                run_dir: str | None, options: SpecOptions,
                environ: Mapping[str, str] | None = None) -> list[ProcessSpec]:
    """The ProcessSpec of each node: exactly roslaunch's argv/env/cwd plus our run settings."""
    base = dict(os.environ if environ is None else environ)
    # nodes write to pipes, not a TTY: without this, Python nodes block-buffer their output
    # and the console shows it late (roslaunch leaves screen nodes on the TTY instead)
    base.setdefault("PYTHONUNBUFFERED", "1")
    base["PATH"] = path_with_interpreter(base.get("PATH", ""), sys.executable)
    base.update(layer_env(base))   # rospy & co. for Python nodes without ROS (ros1/activation)
    specs = []
    for counter, node in enumerate(nodes, start=1):
        exe = executables[node.full_name]
        log_name = log_base_name(node.full_name, counter)
        log_file = os.path.join(run_dir, log_name + ".log") if run_dir else None
        argv = node_argv(node, exe, log_file=log_file)
        env = dict(base)
        env.update(node_env(node, master_uri))
        sigint, sigterm = options.node_timeouts.get(node.full_name, (None, None))
        if sigint is None and node.stop_timeout is not None:
            # rosmon's stop-timeout: SIGINT, then that many seconds, then killed
            sigint, sigterm = node.stop_timeout, 0.0 if sigterm is None else sigterm
        specs.append(ProcessSpec(
            name=node.full_name, argv=tuple(argv), env=env,
            cwd=node_cwd(node, exe, base),
            respawn=node.respawn, respawn_delay=node.respawn_delay,
            required=node.required or options.all_required,
            output=output_mode(node, options), log_name=log_name,
            sigint_timeout=options.sigint_timeout if sigint is None else sigint,
            sigterm_timeout=options.sigterm_timeout if sigterm is None else sigterm,
            location=str(node_location(node)) if node.filename else None,
            limits=Limits(node.memory_limit, node.cpu_limit, node.enable_coredumps)))
    return specs


def run_specs(core: Sequence[Node], nodes: Sequence[Node], executables: Mapping[str, str],
              master_uri: str, run_dir: str | None, options: SpecOptions,
              environ: Mapping[str, str] | None = None) -> list[ProcessSpec]:
    """The specs of a run: roscore's nodes first (so they count from 1, as with roslaunch),
    then the plan's. ``--required`` is about the plan's nodes: a core node respawns rather
    than ending the launch. orchestra's own core nodes start with SIGINT held until they can
    take it (``ProcessSpec.sigint_held``): a launch stopped at once ends them quietly."""
    specs = build_specs([*core, *nodes], executables, master_uri, run_dir, options, environ)
    return [replace(spec, required=False,
                    sigint_held=releases_sigint(executables[node.full_name]))
            for node, spec in zip(core, specs, strict=False)] + specs[len(core):]
