"""The launching host's side of remote machines: connections, agents, node commands.

Order of a run with remote nodes (all-or-nothing, like local nodes):

1. ``RemoteSession.open`` -- before the master or any process starts: the ``ssh -M -N``
   master connections of every machine, all at once, each waited for (its control socket
   appears) up to the machine's ``timeout``; then, over them and also all at once, one agent
   per machine (``env ROS_MASTER_URI=URI [ENV_LOADER] python3 -m orchestra.remote.agent
   serve``), which first finds every node's executable there and answers with one JSON line.
   Any failure (host key, refused key, wrong port, env-loader missing, orchestra or a package
   missing) is one error naming the machine, its address and what ssh or the agent said; all
   connections are closed and nothing else was started.
2. ``node_argv`` -- each remote node's local process is ``client.py`` (a bare interpreter,
   standard library only) connected to a local Unix socket that the machine's master
   connection forwards (``-L local:remote``) to the agent's socket: one forwarded channel per
   node, no remote shell or ssh session per node. The supervisor runs it like any node
   (respawn, required, output, stop).
3. ``close`` -- after the supervisor is done: one ``agent reap`` per machine waits (bounded
   by the longest stop timeouts) until no process of the run is left there; then the agents'
   sessions and the connections are closed.

A machine costs one connection and two ssh sessions (the agent's and, at the end, ``reap``),
whatever its number of nodes: forwarded channels are not sessions (sshd's ``MaxSessions``,
10 by default, does not limit them), and a remote login shell -- which often sources ROS
setup files from ``.bashrc`` -- runs once per machine, not once per node. The masters and
agent sessions get the parent-death signal like nodes and are registered with the watchdog,
so a SIGKILLed orchestra drops every connection and every agent stops its nodes.
"""
from __future__ import annotations

import json
import logging
import os
import secrets
import select
import shlex
import shutil
import socket
import subprocess
import sys
import tempfile
import time
import urllib.parse
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

from orchestra.errors import Location, OrchestraError
from orchestra.launch.plan import Machine, Node
from orchestra.remote import payload, ssh
from orchestra.remote.agent import RELEASE_REQUEST, STATS_REQUEST
from orchestra.supervise.reaper import setpriv_prefix

logger = logging.getLogger(__name__)

AGENT = ("python3", "-m", "orchestra.remote.agent")
CLIENT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "client.py")


class RemoteError(OrchestraError):
    """A remote machine that cannot run its nodes (unreachable, refused, missing software)."""


def _location(node: Node) -> Location | None:
    return Location(node.filename, node.line) if node.filename else None


def check_machine_config(machine: Machine, node: Node) -> None:
    """What orchestra refuses in a remote ``<machine>`` before connecting anywhere."""
    if machine.password:
        raise RemoteError(
            f"machine '{machine.name}': password= is not supported: orchestra runs OpenSSH "
            "in batch mode, which never types a password; use a key (ssh-copy-id) or an "
            "ssh agent", _location(node))


def reachable_master_uri(master_uri: str, address: str) -> str:
    """The master URI as ``address`` can reach it.

    A loopback master host (``localhost``) means nothing on another machine: it is replaced
    by this host's own address on the route to ``address`` (the source address the kernel
    picks for it; a UDP ``connect`` sends no packet). Any other host is kept as written.
    """
    parts = urllib.parse.urlsplit(master_uri)
    host = parts.hostname or "localhost"
    if host not in ("localhost", "::1") and not host.startswith("127."):
        return master_uri
    try:
        family = socket.getaddrinfo(address, None)[0][0]
        with socket.socket(family, socket.SOCK_DGRAM) as probe:
            probe.connect((address, 9))
            local = probe.getsockname()[0]
    except OSError:
        return master_uri
    if ":" in local:
        local = f"[{local}]"
    return urllib.parse.urlunsplit((parts.scheme, f"{local}:{parts.port}", parts.path or "/",
                                    "", ""))


def agent_command(machine: Machine, master_uri: str, mode: str, data: dict) -> str:
    """The agent's command line: roslaunch's ``env ROS_MASTER_URI=.. ENV_LOADER cmd`` shape."""
    words = ["env", f"ROS_MASTER_URI={master_uri}"]
    if machine.env_loader:
        words.append(machine.env_loader)
    words += [*AGENT, mode, payload.encode(data)]
    return " ".join(shlex.quote(word) for word in words)


@dataclass
class _Machine:
    """One remote machine of the run: its connection, its agent and their sockets."""

    machine: Machine
    target: ssh.SshTarget
    first_node: Node
    local_socket: str            # this host's end of the forwarding
    remote_socket: str           # the agent's socket on the machine
    master: subprocess.Popen | None = None
    agent: subprocess.Popen | None = None


class RemoteSession:
    """The remote machines of one run: their connections, agents and nodes' commands."""

    def __init__(self, machines: dict[str, Machine], nodes: Sequence[Node],
                 mark: str | None = None, watch: Callable[[int], None] | None = None):
        self.mark = mark
        self.watch = watch
        self.nodes = list(nodes)
        self.program = ssh.ssh_program()
        for node in self.nodes:                  # refused before anything is created
            check_machine_config(machines[node.machine_name or ""], node)
        self.dir = tempfile.mkdtemp(prefix="orchestra-ssh-")
        self.machines: dict[str, _Machine] = {}
        token = secrets.token_hex(8)
        for node in self.nodes:
            machine = machines[node.machine_name or ""]
            if machine.name not in self.machines:
                number = len(self.machines)
                self.machines[machine.name] = _Machine(
                    machine, ssh.target_for(machine, os.path.join(self.dir, f"c{number}")),
                    node, local_socket=os.path.join(self.dir, f"a{number}"),
                    remote_socket=f"/tmp/orchestra-agent-{token}-{number}/s")
        self.max_stop = 0.0

    # ------------------------------------------------------------------ before the run

    def open(self) -> None:
        """Connect every machine and start its agent; RemoteError if any cannot run its nodes."""
        try:
            self._start_masters()
            self._wait_masters()
            self._start_agents()
        except BaseException:
            self.close(reap=False)
            raise

    def _spawn(self, argv: list[str], **kwargs) -> subprocess.Popen:
        """A helper process that dies with orchestra (parent-death signal + watchdog)."""
        popen = subprocess.Popen([*(setpriv_prefix() or ()), *argv], start_new_session=True,
                                 stdin=subprocess.DEVNULL, **kwargs)
        if self.watch is not None:
            self.watch(popen.pid)
        return popen

    def _start_masters(self) -> None:
        for entry in self.machines.values():
            argv = ssh.master_argv(entry.target, self.program,
                                   forward=(entry.local_socket, entry.remote_socket))
            with open(entry.target.control_path + ".err", "wb") as err:
                entry.master = self._spawn(argv, stdout=subprocess.DEVNULL, stderr=err)

    def _wait_masters(self) -> None:
        """Until every control socket exists; the first master that exits is the error."""
        start = time.monotonic()
        waiting = list(self.machines.values())
        while waiting:
            for entry in list(waiting):
                assert entry.master is not None
                control = entry.target.control_path
                if os.path.exists(control):
                    waiting.remove(entry)
                elif entry.master.poll() is not None:
                    raise self._failure(entry, ssh.explain(_read(control + ".err")))
                elif time.monotonic() - start > entry.machine.timeout + 1.0:
                    raise self._failure(entry, f"ssh: no connection within the machine's "
                                               f"timeout ({entry.machine.timeout:g} s)")
            if waiting:
                time.sleep(0.01)

    def _failure(self, entry: _Machine, what: str) -> RemoteError:
        return RemoteError(f"{entry.target.label}: {what}", _location(entry.first_node))

    def _start_agents(self) -> None:
        for name, entry in self.machines.items():
            nodes = [payload.node_to_data(n) for n in self.nodes if (n.machine_name or "") == name]
            data = {"machine": name, "address": entry.machine.address, "mark": self.mark,
                    "nodes": nodes, "socket": entry.remote_socket}
            command = agent_command(entry.machine, "http://localhost:11311/", "serve", data)
            # stderr to a file: nobody reads the agent's pipes during the run, and a full
            # pipe would block it
            with open(entry.target.control_path + ".agent.err", "wb") as err:
                entry.agent = self._spawn(
                    ssh.session_argv(entry.target, command, self.program),
                    stdout=subprocess.PIPE, stderr=err)
        problems = [problem for problem in (self._agent_ready(entry)
                                            for entry in self.machines.values()) if problem]
        if problems:
            raise problems[0]

    def _agent_ready(self, entry: _Machine) -> RemoteError | None:
        """Read the agent's first line (bounded); a failure is explained from its stderr."""
        agent = entry.agent
        assert agent is not None and agent.stdout is not None
        deadline = time.monotonic() + entry.machine.timeout + 30.0
        line = b""
        while not line.endswith(b"\n") and time.monotonic() < deadline:
            ready, _, _ = select.select([agent.stdout], [], [], deadline - time.monotonic())
            if not ready:
                break
            chunk = os.read(agent.stdout.fileno(), 65536)
            if not chunk:
                break
            line += chunk
        if line.endswith(b"\n"):
            try:
                report = json.loads(line)
            except ValueError:
                report = None
            if isinstance(report, dict):
                missing = report.get("missing") or []
                if missing:
                    more = f" (and {len(missing) - 1} more)" if len(missing) > 1 else ""
                    return self._failure(entry, f"{missing[0]}{more}")
                return None
        if agent.poll() is None:
            agent.kill()
        agent.communicate()
        return self._agent_failure(entry, agent.returncode,
                                   _read(entry.target.control_path + ".agent.err"))

    def _agent_failure(self, entry: _Machine, code: int | None, err: str) -> RemoteError:
        loader = entry.machine.env_loader
        if code == 255:
            return self._failure(entry, ssh.explain(err))
        if code in (126, 127) and loader and loader in err:
            return self._failure(entry, f"env-loader {loader}: {ssh.last_line(err)}")
        if "No module named" in err or code == 127:
            return self._failure(entry, "orchestra is not installed there (python3 -m "
                                        f"orchestra.remote.agent: {ssh.last_line(err)}); "
                                        "install it, or make the machine's env-loader put it "
                                        "on the path")
        return self._failure(entry, f"the remote agent failed (exit code {code}): "
                                    f"{ssh.last_line(err)}")

    # ------------------------------------------------------------------ the run

    def node_argv(self, node: Node, master_uri: str, run_id: str, log_name: str,
                  sigint_timeout: float, sigterm_timeout: float) -> list[str]:
        """The local command of a remote node: client.py on the machine's forwarded socket."""
        entry = self.machines[node.machine_name or ""]
        uri = reachable_master_uri(master_uri, entry.machine.address)
        self.max_stop = max(self.max_stop, sigint_timeout + sigterm_timeout)
        data = {"node": payload.node_to_data(node), "master_uri": uri, "run_id": run_id,
                "log_name": log_name, "sigint_timeout": sigint_timeout,
                "sigterm_timeout": sigterm_timeout}
        return [sys.executable, "-I", "-S", CLIENT, entry.local_socket, payload.encode(data)]

    def remote_stats(self, timeout: float = 0.5) -> dict[str, dict[str, Any]]:
        """{node full name: {machine, pid, cpu_percent, rss}} as each machine's agent sees
        its nodes (for ``orchestra status``); a machine that does not answer in ``timeout``
        is left out."""
        found: dict[str, dict[str, Any]] = {}
        for name, entry in self.machines.items():
            try:
                with socket.socket(socket.AF_UNIX) as sock:
                    sock.settimeout(timeout)
                    sock.connect(entry.local_socket)
                    sock.sendall(STATS_REQUEST)
                    data = b""
                    while chunk := sock.recv(65536):
                        data += chunk
                report = json.loads(data)
            except (OSError, ValueError):
                continue
            for node, values in report.items():
                found[node] = {"machine": name, **values}
        return found

    def annotate(self, snapshot: dict[str, Any]) -> dict[str, Any]:
        """A status snapshot with the remote nodes' pid/CPU/RSS from their machines."""
        remote = self.remote_stats()
        for entry in snapshot.get("nodes", ()):
            values = remote.get(entry.get("name"))
            if values is not None and entry.get("pid") is not None:
                entry.update(values)
        return snapshot

    # ------------------------------------------------------------------ after the run

    def close(self, reap: bool = True) -> None:
        """Wait until nothing of the run is left remotely (bounded), then disconnect."""
        if reap and self.mark:
            self._reap()
        self._release_agents()
        helpers = [p for entry in self.machines.values() for p in (entry.agent, entry.master)
                   if p is not None]
        for popen in helpers:
            if popen.poll() is None:
                popen.terminate()
        for popen in helpers:
            try:
                popen.communicate(timeout=5.0)
            except subprocess.TimeoutExpired:
                popen.kill()
                popen.communicate()
        shutil.rmtree(self.dir, ignore_errors=True)

    def _release_agents(self, timeout: float = 5.0) -> None:
        """Ask every agent to end and wait (bounded) until it has, so that nothing of the run
        is left remotely when close() returns. Without this the agent ended only on sshd's
        SIGHUP once our ssh client was gone: a moment after the launch had already exited."""
        waiting = []
        for entry in self.machines.values():
            agent = entry.agent
            if agent is None or agent.poll() is not None:
                continue
            try:
                with socket.socket(socket.AF_UNIX) as sock:
                    sock.settimeout(1.0)
                    sock.connect(entry.local_socket)
                    sock.sendall(RELEASE_REQUEST)
            except OSError:
                continue          # the channel is gone: the agent ends on sshd's SIGHUP
            waiting.append(agent)
        deadline = time.monotonic() + timeout + self.max_stop
        for agent in waiting:
            try:
                agent.wait(max(0.0, deadline - time.monotonic()))
            except subprocess.TimeoutExpired:
                logger.warning("a remote agent did not end in time; closing its session")

    def _reap(self) -> None:
        running = []
        for entry in self.machines.values():
            if entry.master is None or entry.master.poll() is not None:
                continue
            command = agent_command(entry.machine, "http://localhost:11311/", "reap",
                                    {"mark": self.mark, "timeout": self.max_stop + 1.0})
            running.append((entry, subprocess.Popen(
                ssh.session_argv(entry.target, command, self.program),
                stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.PIPE)))
        for entry, proc in running:
            try:
                out, err = proc.communicate(timeout=self.max_stop + entry.machine.timeout + 5)
            except subprocess.TimeoutExpired:
                proc.kill()
                out, err = proc.communicate()
            if proc.returncode != 0:
                logger.warning("%s: could not check for leftover processes: %s",
                               entry.target.label, ssh.explain(err.decode(errors="replace")))
                continue
            try:
                killed = json.loads(out.decode().strip().splitlines()[-1]).get("killed")
            except (ValueError, IndexError):
                killed = None
            if killed:
                logger.warning("%s: killed %d leftover process(es) of this run",
                               entry.target.label, len(killed))


def _read(path: str) -> str:
    try:
        with open(path, encoding="utf-8", errors="replace") as fh:
            return fh.read()
    except OSError:
        return ""
