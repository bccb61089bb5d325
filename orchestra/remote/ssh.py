"""The OpenSSH client command lines orchestra runs, and what their failures mean.

Why the system ``ssh`` (not a Python SSH library, as roslaunch's paramiko): it is what every
robot already has and what users already configured -- ``~/.ssh/config``, keys, the agent,
known_hosts, ProxyJump -- so orchestra honours all of it by not reimplementing any of it.
Every command adds only what orchestra needs:

- ``BatchMode=yes``: never a password or host-key prompt (a launch must not hang on one);
- ``ConnectTimeout`` from the machine's ``timeout``;
- ``ControlPath`` in orchestra's private directory: one master connection per machine
  (``ssh -M -N``), every node a multiplexed session on it (50 nodes = one TCP connection,
  one authentication). A client whose master is gone falls back to its own connection.

``ORCHESTRA_SSH_CONFIG`` names an ssh config file passed as ``-F`` (for tests and for
launches that must not read ``~/.ssh/config``); ``StrictHostKeyChecking`` and every other
policy stay the user's.
"""
from __future__ import annotations

import math
import os
import shutil
from collections.abc import Mapping
from dataclasses import dataclass

from orchestra.errors import OrchestraError
from orchestra.launch.plan import Machine

CONFIG_VARIABLE = "ORCHESTRA_SSH_CONFIG"


@dataclass(frozen=True)
class SshTarget:
    """How to reach one machine: its ssh destination and the options every command shares."""

    machine: str
    address: str
    port: int
    user: str | None
    timeout: float
    control_path: str
    config: str | None = None

    @property
    def label(self) -> str:
        """``machine 'base' (robot@10.0.0.2:22)``: how every error names the machine."""
        user = f"{self.user}@" if self.user else ""
        return f"machine '{self.machine}' ({user}{self.address}:{self.port})"


def ssh_program() -> str:
    path = shutil.which("ssh")
    if path is None:
        raise OrchestraError("remote machines need the OpenSSH client: 'ssh' is not on PATH")
    return path


def target_for(machine: Machine, control_path: str,
               environ: Mapping[str, str] | None = None) -> SshTarget:
    env = os.environ if environ is None else environ
    return SshTarget(machine=machine.name, address=machine.address, port=machine.ssh_port,
                     user=machine.user, timeout=machine.timeout, control_path=control_path,
                     config=env.get(CONFIG_VARIABLE) or None)


def common_options(target: SshTarget) -> list[str]:
    options = ["-F", target.config] if target.config else []
    options += ["-o", "BatchMode=yes",
                "-o", f"ConnectTimeout={max(1, math.ceil(target.timeout))}",
                "-o", f"ControlPath={target.control_path}",
                "-p", str(target.port)]
    if target.user:
        options += ["-l", target.user]
    return options


def master_argv(target: SshTarget, program: str = "ssh",
                forward: tuple[str, str] | None = None) -> list[str]:
    """The connection every session of this machine multiplexes on (no command, no stdin).

    ``forward`` = (local socket, remote socket): a Unix-socket forwarding on it, failing the
    connection if it cannot be set up. ServerAlive* make a dead network visible within ~15 s:
    the master then exits, every channel closes, and the remote agent stops its nodes.
    """
    extra = ["-o", "ExitOnForwardFailure=yes", "-L", f"{forward[0]}:{forward[1]}"] \
        if forward else []
    return [program, *common_options(target), "-M", "-N", "-n", "-T",
            "-o", "ControlPersist=no", "-o", "ServerAliveInterval=5",
            "-o", "ServerAliveCountMax=3", *extra, "--", target.address]


def session_argv(target: SshTarget, command: str, program: str = "ssh") -> list[str]:
    """A multiplexed session running ``command`` (one shell word string) on the machine.

    ``-n``: the session never reads the launching terminal (nodes get no stdin, as with
    roslaunch's remote nodes).
    """
    return [program, *common_options(target), "-n", "-T", "-o", "ControlMaster=no",
            "--", target.address, command]


def last_line(stderr: str) -> str:
    """The line of an stderr that says what went wrong (its own words, one line).

    ssh may print warnings first (``Warning: Permanently added ...``); the reason is the
    last non-empty line that is not such a warning.
    """
    lines = [line.strip() for line in stderr.splitlines() if line.strip()]
    useful = [line for line in lines if not line.startswith(("Warning:", "debug"))]
    return (useful or lines or ["no error message"])[-1][:300]


def explain(stderr: str) -> str:
    """ssh's own failure (exit 255) as one line, prefixed ``ssh:`` when ssh did not."""
    chosen = last_line(stderr)
    return chosen if chosen.startswith("ssh:") else f"ssh: {chosen}"
