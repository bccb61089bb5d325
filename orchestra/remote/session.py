"""The launching host's side of remote machines: connections, the preflight, node commands.

Order of a run with remote nodes (all-or-nothing, like local nodes):

1. ``RemoteSession.open`` -- before the master or any process starts: one ``ssh -M -N``
   master connection per machine, all at once, each waited for (its control socket appears)
   up to the machine's ``timeout``; then, over those connections and also all at once, one
   ``agent check`` per machine, which runs the machine's env-loader and finds every node's
   executable there. Any failure (host key, refused key, wrong port, env-loader missing,
   orchestra or a package missing) is one error naming the machine, its address and what
   ssh or the agent said; the masters are closed and nothing else was started.
2. ``node_argv`` -- each remote node's local process is ``ssh ... -- env ROS_MASTER_URI=URI
   [ENV_LOADER] python3 -m orchestra.remote.agent run PAYLOAD`` multiplexed on its machine's
   master; the supervisor runs it like any node (respawn, required, output, stop).
3. ``close`` -- after the supervisor is done: one ``agent reap`` per machine waits (bounded
   by the longest stop timeouts) until no process of the run is left there, then the master
   connections are closed.

The masters get the parent-death signal like nodes do and are registered with the watchdog,
so a SIGKILLed orchestra drops every connection, and every agent stops its node.
"""
from __future__ import annotations

import json
import logging
import os
import shlex
import shutil
import socket
import subprocess
import tempfile
import time
import urllib.parse
from collections.abc import Callable, Sequence
from dataclasses import dataclass

from orchestra.errors import Location, OrchestraError
from orchestra.launch.plan import Machine, Node
from orchestra.remote import payload, ssh
from orchestra.supervise.reaper import setpriv_prefix

logger = logging.getLogger(__name__)

AGENT = ("python3", "-m", "orchestra.remote.agent")


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
    """The remote command line: roslaunch's ``env ROS_MASTER_URI=.. ENV_LOADER cmd`` shape."""
    words = ["env", f"ROS_MASTER_URI={master_uri}"]
    if machine.env_loader:
        words.append(machine.env_loader)
    words += [*AGENT, mode, payload.encode(data)]
    return " ".join(shlex.quote(word) for word in words)


@dataclass
class _Connection:
    machine: Machine
    target: ssh.SshTarget
    first_node: Node
    popen: subprocess.Popen | None = None
    stderr_path: str = ""


class RemoteSession:
    """The remote machines of one run: their connections and their nodes' commands."""

    def __init__(self, machines: dict[str, Machine], nodes: Sequence[Node],
                 mark: str | None = None, watch: Callable[[int], None] | None = None):
        self.mark = mark
        self.watch = watch
        self.nodes = list(nodes)
        self.program = ssh.ssh_program()
        self.dir = tempfile.mkdtemp(prefix="orchestra-ssh-")
        self.connections: dict[str, _Connection] = {}
        for node in self.nodes:
            machine = machines[node.machine_name or ""]
            check_machine_config(machine, node)
            if machine.name not in self.connections:
                control = os.path.join(self.dir, f"c{len(self.connections)}")
                self.connections[machine.name] = _Connection(
                    machine, ssh.target_for(machine, control), node)
        self.max_stop = 0.0

    # ------------------------------------------------------------------ before the run

    def open(self, master_uri: str = "http://localhost:11311/") -> None:
        """Connect every machine and check it can run its nodes; RemoteError if not."""
        try:
            self._start_masters()
            self._wait_masters()
            self._check_machines(master_uri)
        except BaseException:
            self.close(reap=False)
            raise

    def _start_masters(self) -> None:
        prefix = list(setpriv_prefix() or ())
        for conn in self.connections.values():
            conn.stderr_path = conn.target.control_path + ".err"
            with open(conn.stderr_path, "wb") as err:
                conn.popen = subprocess.Popen(
                    [*prefix, *ssh.master_argv(conn.target, self.program)],
                    stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=err,
                    start_new_session=True)
            if self.watch is not None:
                self.watch(conn.popen.pid)

    def _wait_masters(self) -> None:
        """Until every control socket exists; the first master that exits is the error."""
        start = time.monotonic()
        waiting = dict(self.connections)
        while waiting:
            for name, conn in list(waiting.items()):
                assert conn.popen is not None
                if os.path.exists(conn.target.control_path):
                    del waiting[name]
                elif conn.popen.poll() is not None:
                    raise self._failure(conn, ssh.explain(self._stderr(conn)))
                elif time.monotonic() - start > conn.machine.timeout + 1.0:
                    raise self._failure(conn, f"ssh: no connection within the machine's "
                                              f"timeout ({conn.machine.timeout:g} s)")
            if waiting:
                time.sleep(0.01)

    def _stderr(self, conn: _Connection) -> str:
        try:
            with open(conn.stderr_path, encoding="utf-8", errors="replace") as fh:
                return fh.read()
        except OSError:
            return ""

    def _failure(self, conn: _Connection, what: str) -> RemoteError:
        return RemoteError(f"{conn.target.label}: {what}", _location(conn.first_node))

    def _check_machines(self, master_uri: str) -> None:
        running = {}
        for name, conn in self.connections.items():
            nodes = [payload.node_to_data(n) for n in self.nodes
                     if (n.machine_name or "") == name]
            command = agent_command(conn.machine, master_uri, "check", {"nodes": nodes})
            running[name] = subprocess.Popen(
                ssh.session_argv(conn.target, command, self.program),
                stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
        problems: list[RemoteError] = []
        for name, proc in running.items():
            conn = self.connections[name]
            try:
                out, err = proc.communicate(timeout=conn.machine.timeout + 30.0)
            except subprocess.TimeoutExpired:
                proc.kill()
                out, err = proc.communicate()
            problem = self._check_result(conn, proc.returncode, out.decode(errors="replace"),
                                         err.decode(errors="replace"))
            if problem is not None:
                problems.append(problem)
        if problems:
            raise problems[0]

    def _check_result(self, conn: _Connection, code: int | None, out: str,
                      err: str) -> RemoteError | None:
        loader = conn.machine.env_loader
        if code == 255:
            return self._failure(conn, ssh.explain(err))
        if code in (126, 127) and loader and loader in err:
            return self._failure(conn, f"env-loader {loader}: {ssh.last_line(err)}")
        if "No module named" in err or code == 127:
            return self._failure(conn, "orchestra is not installed there (python3 -m "
                                       f"orchestra.remote.agent: {ssh.last_line(err)}); install "
                                       "it, or make the machine's env-loader put it on the "
                                       "path")
        try:
            report = json.loads(out.strip().splitlines()[-1])
        except (ValueError, IndexError):
            return self._failure(conn, f"the remote check failed (exit code {code}): "
                                       f"{ssh.last_line(err)}")
        missing = report.get("missing") or []
        if missing:
            more = f" (and {len(missing) - 1} more)" if len(missing) > 1 else ""
            return self._failure(conn, f"{missing[0]}{more}")
        return None

    # ------------------------------------------------------------------ the run

    def node_argv(self, node: Node, master_uri: str, run_id: str, log_name: str,
                  sigint_timeout: float, sigterm_timeout: float) -> list[str]:
        """The local command of a remote node: a multiplexed ssh session running the agent."""
        conn = self.connections[node.machine_name or ""]
        uri = reachable_master_uri(master_uri, conn.machine.address)
        self.max_stop = max(self.max_stop, sigint_timeout + sigterm_timeout)
        data = {"node": payload.node_to_data(node), "machine": conn.machine.name,
                "address": conn.machine.address, "master_uri": uri, "run_id": run_id,
                "log_name": log_name, "mark": self.mark,
                "sigint_timeout": sigint_timeout, "sigterm_timeout": sigterm_timeout}
        return ssh.session_argv(conn.target, agent_command(conn.machine, uri, "run", data),
                                self.program)

    def master_uri_for(self, node: Node, master_uri: str) -> str:
        return reachable_master_uri(master_uri,
                                    self.connections[node.machine_name or ""].machine.address)

    # ------------------------------------------------------------------ after the run

    def close(self, reap: bool = True) -> None:
        """Wait until nothing of the run is left remotely (bounded), then disconnect."""
        if reap and self.mark:
            self._reap()
        for conn in self.connections.values():
            if conn.popen is not None and conn.popen.poll() is None:
                conn.popen.terminate()
        for conn in self.connections.values():
            if conn.popen is not None:
                try:
                    conn.popen.wait(timeout=5.0)
                except subprocess.TimeoutExpired:
                    conn.popen.kill()
                    conn.popen.wait()
        shutil.rmtree(self.dir, ignore_errors=True)

    def _reap(self) -> None:
        running = []
        for conn in self.connections.values():
            if conn.popen is None or conn.popen.poll() is not None:
                continue
            command = agent_command(conn.machine, "http://localhost:11311/", "reap",
                                    {"mark": self.mark, "timeout": self.max_stop + 1.0})
            running.append((conn, subprocess.Popen(
                ssh.session_argv(conn.target, command, self.program),
                stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.PIPE)))
        for conn, proc in running:
            try:
                out, err = proc.communicate(timeout=self.max_stop + conn.machine.timeout + 5)
            except subprocess.TimeoutExpired:
                proc.kill()
                out, err = proc.communicate()
            if proc.returncode != 0:
                logger.warning("%s: could not check for leftover processes: %s",
                               conn.target.label, ssh.explain(err.decode(errors="replace")))
                continue
            try:
                killed = json.loads(out.decode().strip().splitlines()[-1]).get("killed")
            except (ValueError, IndexError):
                killed = None
            if killed:
                logger.warning("%s: killed %d leftover process(es) of this run",
                               conn.target.label, len(killed))
