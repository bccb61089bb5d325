"""The remote end of one ssh session: runs ONE node on this machine for a launch elsewhere.

Started by the launching host as ``env ROS_MASTER_URI=URI [ENV_LOADER] python3 -m
orchestra.remote.agent run PAYLOAD`` (roslaunch starts ``ENV_LOADER roslaunch -c NAME ...``
the same way; its child then builds each node's process). The agent builds the node's argv,
environment and working directory with the very functions local nodes use
(``supervise/command.py``), so a remote node is started exactly as roslaunch's remote child
would start it: the executable found in THIS machine's packages, ``__log:=`` in this
machine's log directory, the environment the env-loader made plus ROS_MASTER_URI,
ROS_NAMESPACE and the node's ``<env>``.

Why an agent and not the node as the ssh command: OpenSSH does not deliver signals or a
hang-up to a command without a terminal, so a node run directly would outlive a lost
connection or a killed orchestra. The agent owns the node's process group and watches its
own stdout, which is the ssh channel: when the channel closes (local stop: the supervisor
signals the local ssh client; orchestra killed: its watchdog/parent-death signal kills the
client; network gone: the master connection times out) the channel reports an error, and the agent
stops the node as a local stop would (SIGINT, SIGTERM after the SIGINT timeout, SIGKILL
after the SIGTERM timeout) and SIGKILLs whatever is left in the node's group. The node's
output is relayed to the channel (the launching host prefixes and logs it) and also copied
into this machine's log directory. The exit status is the node's (128+N for signal N, as a
shell reports it).

Other modes: ``check`` (before anything starts: is every executable there?) and ``reap``
(at the end of a run: wait, bounded, until no process of the run is left, then SIGKILL).
"""
from __future__ import annotations

import json
import os
import select
import signal
import subprocess
import sys
import time
from collections.abc import Mapping
from typing import Any, BinaryIO

from orchestra.errors import OrchestraError
from orchestra.launch.plan import Node
from orchestra.remote import payload
from orchestra.supervise.command import (
    find_node_executable,
    node_argv,
    node_cwd,
    node_env,
    path_with_interpreter,
)
from orchestra.supervise.output import prepare_run_log_dir
from orchestra.supervise.reaper import MARK_VARIABLE, child_setup, marked_pids

_READ = 65536


def node_environment(base: Mapping[str, str], node: Node, master_uri: str, address: str,
                     mark: str | None, executable: str) -> dict[str, str]:
    """The remote node's environment: roslaunch's setup_env on the agent's environment.

    Beyond roslaunch: when neither the env-loader nor the node set ROS_IP/ROS_HOSTNAME, the
    node advertises the machine's ``address`` (ROS_HOSTNAME) -- the name the launching host
    already reaches it by -- instead of a host name other machines may not resolve.
    """
    env = dict(base)
    env.setdefault("PYTHONUNBUFFERED", "1")
    env["PATH"] = path_with_interpreter(env.get("PATH", ""), executable)
    added = node_env(node, master_uri)
    if not any(env.get(key) or added.get(key) for key in ("ROS_IP", "ROS_HOSTNAME")):
        env["ROS_HOSTNAME"] = address
    env.pop("ROS_NAMESPACE", None)       # roslaunch: the node's namespace, or none
    env.update(added)
    if mark:
        env[MARK_VARIABLE] = mark
    return env


def exit_status(returncode: int) -> int:
    """Popen's returncode as a shell reports it: 128+N for a death by signal N."""
    return 128 - returncode if returncode < 0 else returncode


class NodeRun:
    """One node process: its pipes relayed to ours and to log files, stopped when asked."""

    def __init__(self, argv: list[str], env: dict[str, str], cwd: str, log_base: str,
                 sigint_timeout: float, sigterm_timeout: float):
        os.makedirs(cwd, exist_ok=True)
        self.proc = subprocess.Popen(argv, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
                                     stderr=subprocess.PIPE, cwd=cwd, env=env,
                                     start_new_session=True,
                                     preexec_fn=child_setup(os.getpid()))
        self.timeouts = (sigint_timeout, sigterm_timeout)
        self.logs: dict[int, BinaryIO] = {}
        self.sinks: dict[int, int | None] = {}
        assert self.proc.stdout is not None and self.proc.stderr is not None
        for stream, sink, suffix in ((self.proc.stdout, 1, "stdout"),
                                     (self.proc.stderr, 2, "stderr")):
            self.logs[stream.fileno()] = open(f"{log_base}-{suffix}.log", "ab")
            self.sinks[stream.fileno()] = sink
        self.escalation: list[tuple[float, int]] = []

    def request_stop(self) -> None:
        """SIGINT now; SIGTERM and SIGKILL later if the node is still there (idempotent)."""
        if self.escalation or self.proc.returncode is not None:
            return
        now = time.monotonic()
        first, second = self.timeouts
        self.escalation = [(now + first, signal.SIGTERM), (now + first + second, signal.SIGKILL)]
        self._signal(signal.SIGINT)

    def channel_lost(self) -> None:
        """The ssh channel closed: nobody relays output any more; stop the node."""
        self.sinks = dict.fromkeys(self.sinks)
        self.request_stop()

    def _signal(self, sig: int) -> None:
        try:
            os.killpg(self.proc.pid, sig)
        except (ProcessLookupError, PermissionError):
            pass

    def escalate(self) -> float | None:
        """Send what is due; seconds until the next step (None: nothing pending)."""
        now = time.monotonic()
        while self.escalation and self.escalation[0][0] <= now:
            self._signal(self.escalation.pop(0)[1])
        return max(0.0, self.escalation[0][0] - now) if self.escalation else None

    def relay(self, fd: int) -> bool:
        """Copy what the node wrote on ``fd``; False at its end."""
        try:
            data = os.read(fd, _READ)
        except OSError:
            data = b""
        if not data:
            return False
        self.logs[fd].write(data)
        self.logs[fd].flush()
        sink = self.sinks[fd]
        if sink is not None:
            try:
                os.write(sink, data)
            except OSError:          # the channel is gone: keep the remote log only
                self.sinks[fd] = None
        return True

    def finish(self) -> int:
        self._signal(signal.SIGKILL)     # helpers left in the node's group die with it
        for log in self.logs.values():
            log.close()
        return exit_status(self.proc.returncode if self.proc.returncode is not None else -9)


def _wakeup_pipe() -> int:
    """A pipe that becomes readable on SIGINT/SIGTERM/SIGHUP (sshd, or a local admin)."""
    read_fd, write_fd = os.pipe()
    os.set_blocking(write_fd, False)
    signal.set_wakeup_fd(write_fd)
    for sig in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP):
        signal.signal(sig, lambda *_: None)
    signal.signal(signal.SIGPIPE, signal.SIG_IGN)   # a closed channel is an EPIPE to handle
    return read_fd


def supervise(run: NodeRun, channel_fd: int) -> int:
    """Relay output until the node is gone; its stop starts when ``channel_fd`` breaks.

    ``channel_fd`` is our stdout, the ssh channel: polled for errors only (no events
    asked), it reports POLLERR/POLLHUP the moment sshd closes the session, whatever the
    reason. (Our stdin would not do: the ssh client sends its EOF right away, as it must
    not read the launching terminal.)
    """
    wake = _wakeup_pipe()
    poller = select.poll()
    roles: dict[int, str] = {channel_fd: "channel", wake: "signal"}
    poller.register(channel_fd, 0)
    poller.register(wake, select.POLLIN)
    for fd in run.logs:
        roles[fd] = "output"
        poller.register(fd, select.POLLIN)
    exit_fd: int | None = None
    try:
        exit_fd = os.pidfd_open(run.proc.pid)
        roles[exit_fd] = "exit"
        poller.register(exit_fd, select.POLLIN)
    except (AttributeError, OSError):
        pass
    open_outputs = len(run.logs)
    drain_until: float | None = None
    while True:
        pending = run.escalate()
        limits = [x for x in (pending, None if exit_fd is not None else 0.2) if x is not None]
        if drain_until is not None:
            limits.append(max(0.0, drain_until - time.monotonic()))
        timeout_ms = None if not limits else int(min(limits) * 1000) + 1
        for fd, _ in poller.poll(timeout_ms):
            role = roles.get(fd)
            if role == "channel":
                poller.unregister(fd)
                run.channel_lost()
            elif role == "signal":
                os.read(wake, 512)
                run.request_stop()
            elif role == "output" and not run.relay(fd):
                poller.unregister(fd)
                open_outputs -= 1
            elif role == "exit":
                poller.unregister(fd)
                os.close(fd)
                roles.pop(fd)
        if run.proc.poll() is not None:
            if drain_until is None:
                run._signal(signal.SIGKILL)
                drain_until = time.monotonic() + 0.5   # grandchildren may hold the pipes
            if open_outputs == 0 or time.monotonic() >= drain_until:
                return run.finish()


def run_node(data: dict[str, Any]) -> int:
    node = payload.node_from_data(data["node"])
    where = f"orchestra agent on machine '{data['machine']}'"
    try:
        exe = find_node_executable(node)
        log_dir = prepare_run_log_dir(data["run_id"])
        argv = node_argv(node, exe, log_file=os.path.join(log_dir, data["log_name"] + ".log"))
        env = node_environment(os.environ, node, data["master_uri"], data["address"],
                               data.get("mark"), sys.executable)
        cwd = node_cwd(node, exe, env)
        run = NodeRun(argv, env, cwd, os.path.join(log_dir, data["log_name"]),
                      float(data["sigint_timeout"]), float(data["sigterm_timeout"]))
    except OrchestraError as exc:
        sys.stderr.write(f"{where}: {exc}\n")
        return 2
    except OSError as exc:
        sys.stderr.write(f"{where}: node '{node.full_name}': cannot start: {exc}\n")
        return 2
    return supervise(run, sys.stdout.fileno())


def check_nodes(data: dict[str, Any]) -> int:
    """Print which of the nodes cannot be started here (JSON), before anything starts."""
    missing = []
    for item in data["nodes"]:
        node = payload.node_from_data(item)
        try:
            find_node_executable(node)
            node_argv(node, "x")
        except OrchestraError as exc:
            missing.append(str(exc))
    sys.stdout.write(json.dumps({"missing": missing, "python": sys.executable}) + "\n")
    return 0


def reap(data: dict[str, Any]) -> int:
    """Wait (bounded) until no process of the run is left here, then SIGKILL the rest."""
    deadline = time.monotonic() + float(data["timeout"])
    left = marked_pids(data["mark"])
    while left and time.monotonic() < deadline:
        time.sleep(0.05)
        left = marked_pids(data["mark"])
    for pid in left:
        try:
            os.kill(pid, signal.SIGKILL)
        except (ProcessLookupError, PermissionError):
            pass
    sys.stdout.write(json.dumps({"killed": left}) + "\n")
    return 0


MODES = {"run": run_node, "check": check_nodes, "reap": reap}


def main(argv: list[str]) -> int:
    if len(argv) != 3 or argv[1] not in MODES:
        sys.stderr.write("usage: python3 -m orchestra.remote.agent run|check|reap PAYLOAD\n"
                         "(started by orchestra launch over ssh; not for direct use)\n")
        return 2
    try:
        data = payload.decode(argv[2])
    except ValueError as exc:
        sys.stderr.write(f"orchestra agent: bad payload: {exc}\n")
        return 2
    return MODES[argv[1]](data)


if __name__ == "__main__":
    sys.exit(main(sys.argv))
