"""Test harness for node processes: a master per test, processes that report JSON lines.

Imported by tests/test_node_*.py (which put this directory on sys.path). Every process
started here is killed by the fixture's finalizer; every server uses an ephemeral port.
"""
from __future__ import annotations

import contextlib
import json
import os
import queue
import signal
import socket
import subprocess
import sys
import threading
import time
import xmlrpc.client
from pathlib import Path

import psutil

HERE = Path(__file__).resolve().parent

ADD_TWO_INTS = "int64 a\nint64 b\n---\nint64 sum\n"
NUM_MSG = "# a custom message\nint64 num\nstring label\ntime stamp\nfloat32[3] xyz\n"


def make_test_package(root: Path) -> Path:
    """A catkin package ``test_msgs`` with one .msg and one .srv, under ``root``."""
    pkg = root / "test_msgs"
    (pkg / "msg").mkdir(parents=True, exist_ok=True)
    (pkg / "srv").mkdir(parents=True, exist_ok=True)
    (pkg / "package.xml").write_text(
        '<package format="2"><name>test_msgs</name><version>0.0.1</version>'
        '<description>t</description><maintainer email="a@b.c">a</maintainer>'
        '<license>BSD</license></package>\n')
    (pkg / "msg" / "Num.msg").write_text(NUM_MSG)
    (pkg / "srv" / "AddTwoInts.srv").write_text(ADD_TWO_INTS)
    return root


def free_port() -> int:
    """A TCP port nothing listens on right now (for a master of the test's own)."""
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]


def cpu_seconds(pid: int) -> float:
    """CPU time (user + system) a process has used so far; infinite once it is gone."""
    try:
        times = psutil.Process(pid).cpu_times()
    except psutil.NoSuchProcess:
        return float("inf")
    return times.user + times.system


def wait_for_cpu(proc: subprocess.Popen, seconds: float, within: float = 10.0) -> None:
    """Return once ``proc`` has used ``seconds`` of CPU (a moment of its start-up, whatever
    the machine's load), has ended, or ``within`` s have passed: a process that goes idle
    sooner never reaches a later moment."""
    deadline = time.monotonic() + within
    while (cpu_seconds(proc.pid) < seconds and proc.poll() is None
           and time.monotonic() < deadline):
        time.sleep(0.005)


def demo_package(ws: Path, nodes: dict[str, str], name: str = "demo") -> Path:
    """A catkin package ``name`` under ``ws`` whose ``nodes/`` holds executable scripts."""
    pkg = ws / name
    (pkg / "nodes").mkdir(parents=True)
    (pkg / "package.xml").write_text(
        f"<package format='2'><name>{name}</name><version>0.0.0</version><description>d"
        "</description><maintainer email='a@b.c'>a</maintainer><license>BSD</license></package>")
    for exe, text in nodes.items():
        path = pkg / "nodes" / exe
        path.write_text(text)
        path.chmod(0o755)
    return pkg


class NodeProcess:
    """A child process whose stdout JSON lines are collected by a reader thread."""

    def __init__(self, argv: list[str], env: dict[str, str], stdin: int | None = None):
        self.argv = argv
        self.proc = subprocess.Popen(argv, env=env, stdin=stdin, stdout=subprocess.PIPE,
                                     stderr=subprocess.PIPE, text=True)
        self.lines: queue.Queue = queue.Queue()
        self.seen: list = []
        self.stderr_lines: list[str] = []
        self._readers = [threading.Thread(target=self._read, daemon=True),
                         threading.Thread(target=self._read_err, daemon=True)]
        for reader in self._readers:
            reader.start()

    def _read(self) -> None:
        for line in self.proc.stdout:
            line = line.strip()
            if not line:
                continue
            try:
                self.lines.put(json.loads(line))
            except ValueError:
                self.lines.put({"text": line})

    def _read_err(self) -> None:
        for line in self.proc.stderr:
            self.stderr_lines.append(line.rstrip("\n"))

    def expect(self, predicate, timeout: float = 10.0):
        """The first (new) JSON line for which ``predicate`` holds; AssertionError on timeout."""
        deadline = time.monotonic() + timeout
        while True:
            remaining = deadline - time.monotonic()
            if remaining <= 0:
                raise AssertionError(f"{self.argv[1:3]}: nothing matched within {timeout}s; "
                                     f"seen {self.seen[-5:]}; stderr {self.stderr_lines[-10:]}")
            try:
                item = self.lines.get(timeout=min(remaining, 0.2))
            except queue.Empty:
                continue
            self.seen.append(item)
            if predicate(item):
                return item

    def messages(self, timeout: float = 10.0):
        return self.expect(lambda d: "msg" in d, timeout)["msg"]

    def ready(self, timeout: float = 15.0) -> dict:
        return self.expect(lambda d: "ready" in d, timeout)

    def signal(self, sig: int) -> None:
        if self.proc.poll() is None:
            self.proc.send_signal(sig)

    def wait(self, timeout: float = 10.0) -> int:
        return self.proc.wait(timeout)

    def kill(self) -> None:
        if self.proc.poll() is None:
            self.proc.kill()
        try:
            self.proc.wait(5)
        except subprocess.TimeoutExpired:
            pass

    def close_pipes(self, timeout: float = 2.0) -> None:
        """Once the process ended: let the readers reach the end of its output, then close
        the pipes (left to the garbage collector they are unclosed files, ResourceWarning).
        A pipe a reader still reads (a grandchild keeps it open) is left alone."""
        for reader in self._readers:
            reader.join(timeout)
        if self.proc.stdin is not None:
            with contextlib.suppress(OSError):
                self.proc.stdin.close()
        if not any(reader.is_alive() for reader in self._readers):
            for pipe in (self.proc.stdout, self.proc.stderr):
                if pipe is not None:
                    pipe.close()


ROS_PYTHON = "/usr/bin/python3"   # Debian's Python, where its real ROS 1 tools live


def run_all(jobs: list[tuple[tuple[str, ...], list[str], dict[str, str]]], timeout: float = 20
            ) -> list[subprocess.CompletedProcess]:
    """Run ``(label, argv, env)`` jobs at once and wait for each (killed after ``timeout``).

    Independent look-ups run concurrently: each is an interpreter start-up (half a second for
    a real ROS tool), and the modules must stay fast. Results keep the jobs' order and labels.
    """
    procs = [subprocess.Popen(argv, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                              text=True) for _, argv, env in jobs]
    results = []
    for (label, _, _), proc in zip(jobs, procs, strict=False):
        try:
            out, err = proc.communicate(timeout=timeout)
        except subprocess.TimeoutExpired:
            proc.kill()
            out, err = proc.communicate()
        results.append(subprocess.CompletedProcess(label, proc.returncode, out, err))
    return results


class OneShotProxy:
    """An XML-RPC proxy whose every call has a connection of its own, closed afterwards
    (``group.master().getSystemState(...)`` leaves no socket to the garbage collector)."""

    def __init__(self, uri: str):
        self.uri = uri

    def __getattr__(self, method: str):
        def call(*args):
            with xmlrpc.client.ServerProxy(self.uri) as proxy:
                return getattr(proxy, method)(*args)
        return call


class ProcessGroup:
    """Node processes started against one master; ``close()`` stops them, kills stragglers."""

    #: what ``close()`` sends first; what is still running 3 s later is killed
    stop_signal = signal.SIGINT

    def __init__(self, master_uri: str):
        self.master_uri = master_uri
        self.procs: list[NodeProcess] = []

    def _start(self, argv: list[str], env: dict[str, str]) -> NodeProcess:
        proc = NodeProcess(argv, env)
        self.procs.append(proc)
        return proc

    def master(self) -> OneShotProxy:
        return OneShotProxy(self.master_uri)

    def run_all(self, *commands: tuple[str, ...], timeout: float = 20
                ) -> list[subprocess.CompletedProcess]:
        """``orchestra ...`` commands (in ``self.orch_env``) and real ROS tools such as
        ``rosnode ...`` (Debian's, in ``self.ros_env``), concurrently, results in order."""
        jobs = []
        for argv in commands:
            if argv[0] == "orchestra":
                jobs.append((argv, [sys.executable, "-m", "orchestra", *argv[1:]],
                             self.orch_env))
            else:
                jobs.append((argv, [ROS_PYTHON, f"/usr/bin/{argv[0]}", *argv[1:]],
                             self.ros_env))
        return run_all(jobs, timeout)

    def close(self) -> None:
        for proc in self.procs:
            if proc.proc.poll() is None:
                proc.signal(self.stop_signal)
        deadline = time.monotonic() + 3
        for proc in self.procs:
            try:
                proc.proc.wait(max(0.1, deadline - time.monotonic()))
            except subprocess.TimeoutExpired:
                proc.kill()
        for proc in self.procs:
            proc.close_pipes()


class Nodes(ProcessGroup):
    """Starts fixture node scripts against one master; ``close()`` kills what is left."""

    stop_signal = signal.SIGTERM

    def __init__(self, master_uri: str, package_path: Path):
        super().__init__(master_uri)
        self.env = dict(os.environ, ROS_MASTER_URI=master_uri,
                        ROS_PACKAGE_PATH=str(package_path), PYTHONUNBUFFERED="1")
        self.env.pop("ROS_NAMESPACE", None)

    def start(self, script: str, *args: str, env: dict[str, str] | None = None) -> NodeProcess:
        return self._start([sys.executable, str(HERE / script), *args],
                           dict(self.env, **(env or {})))

    def start_orchestra(self, *args: str) -> NodeProcess:
        """A long-running ``orchestra ...`` command (e.g. ``topic pub -r``)."""
        return self._start([sys.executable, "-m", "orchestra", *args], dict(self.env))


def wait_for(predicate, timeout: float = 10.0, interval: float = 0.05):
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        value = predicate()
        if value:
            return value
        time.sleep(interval)
    raise AssertionError(f"condition not met within {timeout}s")
