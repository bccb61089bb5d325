"""How a plan node becomes a process: its argv, its environment and its working directory.

These are pure functions of the plan node (plus the package index for the executable), so
the very same code answers ``orchestra launch --dump-plan`` (the ``exec`` table compared
against roslaunch in ../shared/compat/argv) and builds what the supervisor really exec's.
The rules follow roslaunch 1.16's ``create_local_process_args`` / ``setup_env``:

- argv = launch-prefix words + executable + shell-split ``args`` + ``from:=to`` remaps +
  ``__name:=NAME`` (+ ``__log:=FILE``, added by the runner because it names a run-specific
  file);
- env = parent env + ROS_MASTER_URI + ROS_NAMESPACE (the node's namespace without its
  trailing slash, only when not ``/``) + the node's ``<env>`` settings, which win;
- cwd = ROS_HOME by default, the current directory for ``cwd="cwd"`` and the executable's
  directory for ``cwd="node"`` (roslaunch takes the directory of argv[0], which is the
  launch-prefix's program when there is one: a bug we do not copy).
"""
from __future__ import annotations

import os
import shlex
from collections.abc import Mapping
from typing import Any

from orchestra.errors import Location, OrchestraError
from orchestra.launch.plan import LaunchPlan, Node
from orchestra.packages import find_executable
from orchestra.rosdirs import ros_home


class ExecutableNotFound(OrchestraError):
    """A node whose ``type`` is not an executable file of its package."""


class BadNodeCommand(OrchestraError):
    """A node whose ``args`` or ``launch-prefix`` cannot be shell-split (unbalanced quotes)."""


def _location(node: Node) -> Location | None:
    return Location(node.filename, node.line) if node.filename else None


def find_node_executable(node: Node) -> str:
    """The absolute path of the node's executable, or ExecutableNotFound naming file:line."""
    if not node.type:
        raise ExecutableNotFound(f"node '{node.name}' has no type", _location(node))
    try:
        path = find_executable(node.package, node.type)
    except OrchestraError as exc:
        raise ExecutableNotFound(
            f"node '{node.full_name}': {exc.message}", _location(node)) from None
    if not path:
        raise ExecutableNotFound(
            f"node '{node.full_name}': cannot find executable '{node.type}' in package "
            f"'{node.package}' (the file must exist in the package and be executable: chmod +x)",
            _location(node))
    return os.path.abspath(path)


def _split(text: str | None, what: str, node: Node) -> list[str]:
    if not text:
        return []
    try:
        return shlex.split(text)
    except ValueError as exc:
        raise BadNodeCommand(
            f"node '{node.full_name}': {what} {text!r} cannot be split into words: {exc}",
            _location(node)) from None


def node_argv(node: Node, executable: str | None = None, log_file: str | None = None) -> list[str]:
    """The exact argv roslaunch would exec for ``node`` (``__log:=`` only when ``log_file``)."""
    exe = executable if executable is not None else find_node_executable(node)
    argv = _split(node.launch_prefix, "launch-prefix", node) + [exe]
    argv += _split(node.args, "args", node)
    argv += [f"{src}:={dst}" for src, dst in node.remap_args]
    argv.append(f"__name:={node.name}")
    if log_file is not None:
        argv.append(f"__log:={log_file}")
    return argv


def node_env(node: Node, master_uri: str | None = None) -> dict[str, str]:
    """What is ADDED to the parent environment for ``node`` (later keys win).

    ROS_MASTER_URI only when ``master_uri`` is given: the exec table leaves it out because it
    depends on the run, not on the launch file.
    """
    env: dict[str, str] = {}
    if master_uri is not None:
        env["ROS_MASTER_URI"] = master_uri
    ns = node.namespace.rstrip("/")
    if ns:
        env["ROS_NAMESPACE"] = ns
    for name, value in node.env_args:
        env[name] = value
    return env


def node_cwd(node: Node, executable: str, environ: Mapping[str, str] | None = None) -> str:
    """The working directory of the node's process (see module docstring for ``cwd="node"``)."""
    if node.cwd == "node":
        return os.path.dirname(executable)
    if node.cwd == "cwd":
        return os.getcwd()
    if node.cwd == "ros-root":
        env = os.environ if environ is None else environ
        return env.get("ROS_ROOT") or ros_home(environ)
    return ros_home(environ)


def path_with_interpreter(path: str, executable: str) -> str:
    """PATH with the directory of orchestra's own interpreter first, unless already on it.

    Python nodes start with ``#!/usr/bin/env python3``; when orchestra runs from a virtualenv
    that was not activated, that would find a Python without orchestra (and the node runtime)
    installed. roslaunch has no such problem because ROS is installed system-wide.
    """
    directory = os.path.dirname(os.path.abspath(executable))
    entries = [entry for entry in path.split(os.pathsep) if entry]
    if directory in entries:
        return path
    return os.pathsep.join([directory, *entries])


def exec_table(plan: LaunchPlan, include_tests: bool = False) -> dict[str, dict[str, Any]]:
    """``{"/full/name": {"argv": [...], "env": {...}}}`` for ``--dump-plan`` (compat contract).

    A node whose executable cannot be found still gets an entry (argv built around the bare
    type name, plus ``"error"``), because a plan dump must work for packages that ship launch
    files only; running that node is what fails.
    """
    table: dict[str, dict[str, Any]] = {}
    nodes = (*plan.nodes, *plan.tests) if include_tests else plan.nodes
    found: dict[tuple[str, str], str | ExecutableNotFound] = {}
    for node in nodes:
        key = (node.package, node.type)
        if key not in found:
            try:
                found[key] = find_node_executable(node)
            except ExecutableNotFound as exc:
                found[key] = exc
        exe = found[key]
        entry: dict[str, Any] = {}
        if isinstance(exe, ExecutableNotFound):
            entry["error"] = exe.message
            exe = node.type
        try:
            entry["argv"] = node_argv(node, executable=exe)
        except BadNodeCommand as exc:
            entry["argv"] = [exe]
            entry["error"] = exc.message
        entry["env"] = node_env(node)
        table[node.full_name] = dict(argv=entry["argv"], env=entry["env"],
                                     **({"error": entry["error"]} if "error" in entry else {}))
    return table
