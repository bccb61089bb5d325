"""The launch plan: the one immutable result of interpreting a launch file.

Everything downstream (dumps, the master upload, the supervisor) reads only this; nothing
reaches back into launch files. Field names and meanings follow roslaunch's own config objects
so that ``to_json()`` is the JSON contract of ``orchestra launch --dump-plan`` (see
../shared/compat/README.md).
"""
from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any


@dataclass(frozen=True)
class Machine:
    """A ``<machine>``; the ``""`` machine is roslaunch's implicit local default."""

    name: str
    address: str = "localhost"
    env_loader: str | None = None
    ssh_port: int = 22
    user: str | None = None
    password: str | None = None
    timeout: float = 10.0
    assignable: bool = True

    def to_json(self) -> dict[str, Any]:
        return {
            "name": self.name,
            "address": self.address,
            "env_loader": self.env_loader,
            "ssh_port": self.ssh_port,
            "user": self.user,
            "password": self.password,
            "assignable": self.assignable,
            "timeout": self.timeout,
        }


# ``output=`` values: roslaunch's ``log`` and ``screen``, and ``both`` (log file and console,
# as ROS 2's launch has it), an orchestra extension.
OUTPUT_MODES = ("log", "screen", "both")


@dataclass(frozen=True)
class Node:
    """A ``<node>`` resolved: its full name is ``namespace + name``.

    ``args`` is the substituted ``args`` attribute (not yet shell-split); ``remap_args`` are the
    effective remaps (inherited ones overridden by the node's own) in argv order; ``env_args``
    are the ``<env>`` settings in effect for the node.
    """

    package: str
    type: str
    name: str
    namespace: str = "/"
    machine_name: str | None = None
    args: str = ""
    respawn: bool = False
    respawn_delay: float = 0.0
    remap_args: tuple[tuple[str, str], ...] = ()
    env_args: tuple[tuple[str, str], ...] = ()
    output: str | None = None
    cwd: str | None = None
    launch_prefix: str | None = None
    required: bool = False
    filename: str | None = None
    line: int | None = None
    # rosmon's extensions (None/0/False: not set; see docs/compat.md)
    stop_timeout: float | None = None
    memory_limit: int = 0
    cpu_limit: float = 0.0
    enable_coredumps: bool = False

    @property
    def full_name(self) -> str:
        ns = self.namespace if self.namespace.endswith("/") else self.namespace + "/"
        return ns + self.name

    def to_json(self) -> dict[str, Any]:
        return {
            "package": self.package,
            "type": self.type,
            "name": self.name,
            "namespace": self.namespace,
            "machine_name": self.machine_name,
            "args": self.args,
            "respawn": self.respawn,
            "respawn_delay": self.respawn_delay,
            "remap_args": [list(r) for r in self.remap_args],
            "env_args": [list(e) for e in self.env_args],
            "output": self.output,
            "cwd": self.cwd,
            "launch_prefix": self.launch_prefix,
            "required": self.required,
            "filename": self.filename,
            **self._extensions(),
        }

    def _extensions(self) -> dict[str, Any]:
        """rosmon's attributes, only when set: plans without them stay roslaunch's JSON."""
        values = {"stop_timeout": self.stop_timeout, "memory_limit": self.memory_limit,
                  "cpu_limit": self.cpu_limit, "enable_coredumps": self.enable_coredumps}
        return {k: v for k, v in values.items() if v or (k == "stop_timeout" and v is not None)}


@dataclass(frozen=True)
class Test(Node):
    """A ``<test>``: a node run only in test mode, with rostest's extra fields."""

    test_name: str = ""
    time_limit: float = 60.0
    retry: int = 0

    def to_json(self) -> dict[str, Any]:
        data = super().to_json()
        data.update(test_name=self.test_name, time_limit=self.time_limit, retry=self.retry)
        return data


@dataclass(frozen=True)
class ParamAction:
    """A ``<rosparam command="dump">`` or ``command="delete"``, carried out at launch time.

    roslaunch turns these into ``rosparam dump FILE NS`` / ``rosparam delete NAME`` commands
    run in its setup phase: after the master is up, BEFORE clear_params and the parameter
    upload, in document order. So a delete removes what an earlier run left on the server
    (the launch's own params are set afterwards) and a dump records the server as it was
    before this launch's params. ``param`` is the full name (the namespace, for a dump);
    ``file`` is the dump file as written (a relative path is relative to the working
    directory of the launch), None for a delete.
    """

    command: str
    param: str
    file: str | None = None
    filename: str | None = None
    line: int | None = None

    def to_json(self) -> dict[str, Any]:
        return {"command": self.command, "param": self.param, "file": self.file,
                "filename": self.filename, "line": self.line}


def _freeze(mapping: Mapping[str, Any]) -> Mapping[str, Any]:
    return MappingProxyType(dict(mapping))


@dataclass(frozen=True)
class LaunchPlan:
    """What a launch file resolves to.

    ``params`` maps full parameter names to values exactly as roslaunch would store them on the
    parameter server (rosparam dicts flattened to leaves; ``type="yaml"`` values whole; a
    ``command=`` param not executed is ``{"__command__": cmd}``). ``clear_params`` are
    namespaces to clear, in order, before the upload. ``param_actions`` are the
    ``<rosparam>`` dumps and deletes, in document order, run before both (see ParamAction).
    """

    params: Mapping[str, Any] = field(default_factory=dict)
    clear_params: tuple[str, ...] = ()
    nodes: tuple[Node, ...] = ()
    tests: tuple[Test, ...] = ()
    machines: Mapping[str, Machine] = field(default_factory=dict)
    files_loaded: tuple[str, ...] = ()
    param_actions: tuple[ParamAction, ...] = ()

    def __post_init__(self) -> None:
        object.__setattr__(self, "params", _freeze(self.params))
        object.__setattr__(self, "machines", _freeze(self.machines))

    def node(self, full_name: str) -> Node | None:
        """The node (or test) with that full name, or None."""
        for node in (*self.nodes, *self.tests):
            if node.full_name == full_name:
                return node
        return None

    def to_json(self) -> dict[str, Any]:
        """The ``--dump-plan`` document (../shared/compat/README.md)."""
        return {
            "params": dict(self.params),
            "clear_params": list(self.clear_params),
            "nodes": [n.to_json() for n in self.nodes],
            "tests": [t.to_json() for t in self.tests],
            "machines": {name: m.to_json() for name, m in self.machines.items()},
            "files_loaded": list(self.files_loaded),
            "param_actions": [a.to_json() for a in self.param_actions],
        }
