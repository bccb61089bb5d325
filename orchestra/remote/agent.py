"""The remote end of a launch: one agent per machine runs that machine's nodes.

Started once per machine and run by the launching host as ``env ROS_MASTER_URI=URI
[ENV_LOADER] python3 -m orchestra.remote.agent serve PAYLOAD`` -- roslaunch starts its child
``ENV_LOADER roslaunch -c NAME ...`` on each machine the same way. The agent first checks that
every node of the machine can be started here (its executable is found in THIS machine's
packages), reports that as one JSON line, then listens on a private Unix socket, which the
launching host's ssh connection forwards to a local socket. Each node is one connection on
it from the node's local process (``client.py``): the node's payload in, the node's output
and exit status out (framed as client.py describes). So per node there is no remote shell and
no ssh session (a user's ``.bashrc`` sourcing ROS setup files costs ~0.2 s per session), and
the environment the env-loader built once serves every node, as in roslaunch's child.

The agent builds each node's argv, environment and working directory with the very functions
local nodes use (``supervise/command.py``): the executable found here, ``__log:=`` in this
machine's log directory, the agent's environment plus ROS_MASTER_URI, ROS_NAMESPACE and the
node's ``<env>``.

Why not the node itself as the ssh command: OpenSSH delivers no signal or hang-up to a command
without a terminal, so a node run directly would outlive a lost connection or a killed
orchestra. The agent watches each node's connection instead: it ends the moment the node's
local process ends (local stop: the supervisor signals it; orchestra killed: the parent-death
signal and the watchdog kill it and the ssh connection) or the connection is lost (the ssh
master gives up after missed keep-alives). The agent then stops that node as a local stop
would (SIGINT, SIGTERM after the SIGINT timeout, SIGKILL after the SIGTERM timeout) and
SIGKILLs whatever is left in the node's process group. Output is relayed to the connection
(the launching host prefixes and logs it) and also copied into this machine's log directory.
A node's exit status is its own (128+N for signal N, as a shell reports it). When the
agent's own ssh session ends, it stops every node and exits.

Other mode: ``reap`` (at the end of a run: wait, bounded, until no process of the run is left
here, then SIGKILL).
"""
from __future__ import annotations

import functools
import json
import os
import select
import shutil
import signal
import socket
import struct
import subprocess
import sys
import time
from collections.abc import Callable, Mapping
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
from orchestra.supervise.reaper import (
    MARK_VARIABLE,
    check_executable,
    child_setup,
    marked_pids,
    setpriv_prefix,
)
from orchestra.supervise.status import ProcessStats

_READ = 65536
STATS_REQUEST = b"stats\n"      # instead of a node payload: the agent answers with stats
#: instead of a node payload: the run is over, stop every node and end (the session's close)
RELEASE_REQUEST = b"release\n"

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
    """One node process: its pipes relayed to its connection and to log files, stopped on demand.

    ``conn`` is the node's connection (None once it is gone: the remote log still gets
    everything); ``kinds`` maps each of the node's pipes to its frame kind.
    """

    def __init__(self, name: str, argv: list[str], env: dict[str, str], cwd: str,
                 log_base: str, sigint_timeout: float, sigterm_timeout: float,
                 conn: socket.socket):
        self.name = name
        os.makedirs(cwd, exist_ok=True)
        # the node dies with the agent, as local nodes with orchestra (reaper.py: setpriv
        # when present, ~1 ms; else a preexec_fn, which forks the whole interpreter)
        prefix = setpriv_prefix()
        if prefix:
            check_executable(argv[0], env, cwd)
            argv = [*prefix, *argv]
        self.proc = subprocess.Popen(argv, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
                                     stderr=subprocess.PIPE, cwd=cwd, env=env,
                                     start_new_session=True,
                                     preexec_fn=None if prefix else child_setup(os.getpid()))
        self.timeouts = (sigint_timeout, sigterm_timeout)
        self.conn: socket.socket | None = conn
        self.logs: dict[int, BinaryIO] = {}
        self.kinds: dict[int, int] = {}
        assert self.proc.stdout is not None and self.proc.stderr is not None
        for stream, kind, suffix in ((self.proc.stdout, 1, "stdout"),
                                     (self.proc.stderr, 2, "stderr")):
            self.logs[stream.fileno()] = open(f"{log_base}-{suffix}.log", "ab")
            self.kinds[stream.fileno()] = kind
        self.escalation: list[tuple[float, int]] = []
        self.open_outputs = 2
        self.drain_until: float | None = None

    def channel_lost(self) -> None:
        """The connection closed: nobody relays output any more; stop the node."""
        if self.conn is not None:
            self.conn.close()
            self.conn = None
        self.request_stop()

    def send(self, kind: int, data: bytes) -> None:
        """One frame to the node's local process (see client.py); a failure loses the channel."""
        if self.conn is None:
            return
        try:
            self.conn.sendall(frame(kind, data))
        except OSError:
            self.channel_lost()

    def request_stop(self) -> None:
        """SIGINT now; SIGTERM and SIGKILL later if the node is still there (idempotent)."""
        if self.escalation or self.proc.returncode is not None:
            return
        now = time.monotonic()
        first, second = self.timeouts
        self.escalation = [(now + first, signal.SIGTERM), (now + first + second, signal.SIGKILL)]
        self.signal(signal.SIGINT)

    def signal(self, sig: int) -> None:
        try:
            os.killpg(self.proc.pid, sig)
        except (ProcessLookupError, PermissionError):
            pass

    def escalate(self) -> float | None:
        """Send what is due; seconds until the next step (None: nothing pending)."""
        now = time.monotonic()
        while self.escalation and self.escalation[0][0] <= now:
            self.signal(self.escalation.pop(0)[1])
        return max(0.0, self.escalation[0][0] - now) if self.escalation else None

    def relay(self, fd: int) -> bool:
        """Copy what the node wrote on ``fd``; False at its end."""
        try:
            data = os.read(fd, _READ)
        except OSError:
            data = b""
        if not data:
            self.open_outputs -= 1
            return False
        self.logs[fd].write(data)
        self.logs[fd].flush()
        self.send(self.kinds[fd], data)
        return True

    def ended(self) -> bool:
        """True once the node exited and its output is drained (or waited for long enough)."""
        if self.proc.poll() is None:
            return False
        if self.drain_until is None:
            self.signal(signal.SIGKILL)     # helpers left in the node's group die with it
            self.drain_until = time.monotonic() + 0.5   # grandchildren may hold the pipes
        return self.open_outputs == 0 or time.monotonic() >= self.drain_until

    def finish(self) -> int:
        for log in self.logs.values():
            log.close()
        for stream in (self.proc.stdout, self.proc.stderr):
            if stream is not None:
                stream.close()
        return exit_status(self.proc.returncode if self.proc.returncode is not None else -9)


def frame(kind: int, data: bytes) -> bytes:
    """client.py's framing: kind (0 end, 1 stdout, 2 stderr), big-endian length, data."""
    return bytes([kind]) + struct.pack(">I", len(data)) + data


def end_frame(status: int) -> bytes:
    return bytes([0]) + struct.pack(">I", status)


def _wakeup_pipe() -> int:
    """A pipe that becomes readable on SIGINT/SIGTERM/SIGHUP (sshd, or a local admin)."""
    read_fd, write_fd = os.pipe()
    os.set_blocking(write_fd, False)
    signal.set_wakeup_fd(write_fd)
    for sig in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP):
        signal.signal(sig, lambda *_: None)
    signal.signal(signal.SIGPIPE, signal.SIG_IGN)   # a closed channel is an EPIPE to handle
    return read_fd


class Agent:
    """The machine's agent: accepts node connections, runs their nodes, until its session ends.

    One poll loop, no threads. Polled: the listening socket, our own ssh channel (errors
    only: it reports one when sshd closes our session), the signal wake-up pipe, and per node
    its connection (EOF = its local process is gone), its output pipes and its pidfd.
    """

    def __init__(self, data: dict[str, Any]):
        self.machine = data["machine"]
        self.address = data["address"]
        self.mark = data.get("mark")
        self.path = data["socket"]
        os.mkdir(os.path.dirname(self.path), 0o700)    # ours only; an existing one is refused
        self.listener = socket.socket(socket.AF_UNIX)
        self.listener.bind(self.path)
        self.listener.listen(128)
        self.poller = select.poll()
        self.handlers: dict[int, Callable[[int, int], None]] = {}
        self.runs: dict[int, NodeRun] = {}
        self.stats = ProcessStats()
        self.stopping = False
        self.poll_exits = False      # no pidfds here (Linux < 5.3): look for exits every 0.2 s

    def watch(self, fd: int, mask: int, handler: Callable[[int, int], None]) -> None:
        self.poller.register(fd, mask)
        self.handlers[fd] = handler

    def unwatch(self, fd: int) -> None:
        if self.handlers.pop(fd, None) is not None:
            self.poller.unregister(fd)

    def serve(self, channel_fd: int) -> int:
        wake = _wakeup_pipe()
        self.watch(self.listener.fileno(), select.POLLIN, self._accept)
        self.watch(channel_fd, 0, self._stop_all)
        self.watch(wake, select.POLLIN, self._on_signal)
        try:
            while not (self.stopping and not self.runs):
                limits = [x for x in (run.escalate() for run in self.runs.values())
                          if x is not None]
                limits += [max(0.0, run.drain_until - time.monotonic())
                           for run in self.runs.values() if run.drain_until is not None]
                if self.poll_exits and self.runs:
                    limits.append(0.2)
                timeout = int(min(limits) * 1000) + 1 if limits else None
                for fd, events in self.poller.poll(timeout):
                    handler = self.handlers.get(fd)
                    if handler is not None:
                        handler(fd, events)
                for pid, run in list(self.runs.items()):
                    if run.ended():
                        self._finished(pid)
        finally:
            self.listener.close()
            shutil.rmtree(os.path.dirname(self.path), ignore_errors=True)
        return 0

    def _on_signal(self, fd: int, events: int) -> None:
        os.read(fd, 512)
        self._stop_all()

    def _stop_all(self, fd: int | None = None, events: int = 0) -> None:
        """Our own session closed (or a signal): stop every node, accept no more."""
        if fd is not None:
            self.unwatch(fd)
        self.stopping = True
        self.unwatch(self.listener.fileno())
        for run in self.runs.values():
            run.request_stop()

    def _accept(self, fd: int, events: int) -> None:
        conn, _ = self.listener.accept()
        conn.settimeout(10.0)
        data = b""
        try:
            while not data.endswith(b"\n"):
                chunk = conn.recv(_READ)
                if not chunk:
                    break
                data += chunk
        except OSError:
            pass
        if not data.endswith(b"\n"):
            conn.close()
            return
        if data == STATS_REQUEST:
            self._answer_stats(conn)
            return
        if data == RELEASE_REQUEST:
            conn.close()
            self._stop_all()
            return
        try:
            run = self._start(payload.decode(data.decode().strip()), conn)
        except (OrchestraError, OSError, ValueError, KeyError) as exc:
            try:
                conn.sendall(frame(2, f"orchestra agent on machine '{self.machine}': {exc}\n"
                                   .encode()) + end_frame(2))
            except OSError:
                pass
            conn.close()
            return
        pid = run.proc.pid
        self.runs[pid] = run
        self.watch(conn.fileno(), select.POLLIN, functools.partial(self._on_conn, run))
        for out in run.logs:
            self.watch(out, select.POLLIN, functools.partial(self._on_output, run))
        try:
            self.watch(os.pidfd_open(pid), select.POLLIN, self._on_exit)
        except (AttributeError, OSError):
            self.poll_exits = True
        if self.stopping:
            run.request_stop()

    def _answer_stats(self, conn: socket.socket) -> None:
        """For ``orchestra status``: each running node's pid, CPU% and RSS on this machine."""
        report = {}
        for pid, run in self.runs.items():
            cpu, rss = self.stats.sample(pid)
            report[run.name] = {"pid": pid, "cpu_percent": cpu, "rss": rss}
        self.stats.forget_except(set(self.runs))
        try:
            conn.sendall(json.dumps(report).encode())
        except OSError:
            pass
        conn.close()

    def _on_conn(self, run: NodeRun, fd: int, events: int) -> None:
        """The node's connection: EOF (or an error) means its local process is gone."""
        try:
            data = run.conn.recv(4096) if run.conn is not None else b""
        except OSError:
            data = b""
        if not data:
            self.unwatch(fd)
            run.channel_lost()

    def _on_output(self, run: NodeRun, fd: int, events: int) -> None:
        if not run.relay(fd):
            self.unwatch(fd)

    def _on_exit(self, fd: int, events: int) -> None:
        """The pidfd says the node exited; the loop's ``ended`` check takes it from there."""
        self.unwatch(fd)
        os.close(fd)

    def _start(self, data: dict[str, Any], conn: socket.socket) -> NodeRun:
        node = payload.node_from_data(data["node"])
        exe = find_node_executable(node)
        log_dir = prepare_run_log_dir(data["run_id"])
        argv = node_argv(node, exe, log_file=os.path.join(log_dir, data["log_name"] + ".log"))
        env = node_environment(os.environ, node, data["master_uri"], self.address, self.mark,
                               sys.executable)
        return NodeRun(node.full_name, argv, env, node_cwd(node, exe, env),
                       os.path.join(log_dir, data["log_name"]), float(data["sigint_timeout"]),
                       float(data["sigterm_timeout"]), conn)

    def _finished(self, pid: int) -> None:
        run = self.runs.pop(pid)
        code = run.finish()
        for fd in list(run.logs):
            self.unwatch(fd)
        if run.conn is not None:
            self.unwatch(run.conn.fileno())
            try:
                run.conn.sendall(end_frame(code))
            except OSError:
                pass
            run.conn.close()
            run.conn = None


def check_nodes(nodes: list[dict[str, Any]]) -> list[str]:
    """Why each node that cannot be started here cannot (empty: all can)."""
    missing = []
    for item in nodes:
        node = payload.node_from_data(item)
        try:
            find_node_executable(node)
            node_argv(node, "x")
        except OrchestraError as exc:
            missing.append(str(exc))
    return missing


def serve(data: dict[str, Any]) -> int:
    """Check this machine's nodes, report (one JSON line), then run them until released."""
    missing = check_nodes(data["nodes"])
    if missing:
        sys.stdout.write(json.dumps({"missing": missing}) + "\n")
        return 0
    try:
        agent = Agent(data)
    except OSError as exc:
        sys.stderr.write(f"orchestra agent: cannot listen on {data['socket']}: {exc}\n")
        return 2
    sys.stdout.write(json.dumps({"missing": [], "python": sys.executable}) + "\n")
    sys.stdout.flush()
    return agent.serve(sys.stdout.fileno())


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


MODES = {"serve": serve, "reap": reap}


def main(argv: list[str]) -> int:
    if len(argv) != 3 or argv[1] not in MODES:
        sys.stderr.write("usage: python3 -m orchestra.remote.agent serve|reap PAYLOAD\n"
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
