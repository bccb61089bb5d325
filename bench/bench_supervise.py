"""Process-supervision figures, each with a baseline measured in the same run.

    python bench/bench_supervise.py [--quick] [--nodes 100] [--kills 30] [--idle 5]

1. cold start: ``orchestra launch`` of N nodes (embedded master) until its status socket
   reports all N RUNNING; baseline: a fresh Python that Popen's the same N processes.
2. crash -> respawn latency (respawn_delay=0): SIGKILL a node, time until its replacement is
   RUNNING; baseline: one bare Popen of the same command. Target: median < 20 ms.
3. stop of N well-behaved nodes: request_stop -> every node reaped; baseline: SIGINT + wait
   on N bare Popen'd processes. Target: < 0.5 s.
4. supervisor CPU with N idle nodes over a window (orchestra process, embedded master
   included), in % of one core. Target: < 1 %.
5. against the real ROS 1 roslaunch (Debian's 1.15, /usr/bin/roslaunch), the same launch file
   of N trivial sleeping nodes, each launcher starting its own master on a free port, both
   probed the same way (the launcher's descendant processes running the node's program):
   start until all N node processes run, and SIGINT to the launcher until it and every node
   are gone (interleaved, medians), once with ``#!/usr/bin/python3`` nodes (100 interpreter
   start-ups on the same cores: a floor both sides share) and once with native nodes (a tiny
   C program built with ``cc``, as roscpp nodes are native: what the launchers themselves
   cost; skipped without a compiler); a launch whose nodes ignore SIGINT (default timeouts,
   then ``--sigint-timeout``); and the processes left running after the launcher is
   SIGKILLed (orphans, then killed). Skipped with a message when roslaunch is missing.
   With each start row, where the CPU went until the last node ran (the scheduler's own
   accounting, /proc/PID/task/TID/schedstat): the launcher process, its other processes,
   the nodes, and what the cores had in that time. Where ``perf`` can trace (root, or a low
   perf_event_paranoid), each start row is also given by the kernel's own exec timestamps
   (``sched:sched_process_exec``): launcher Popen until the kernel exec'd the last node
   program, free of the probe's polling lag (the probe runs in its own session and so waits
   its turn among the starting interpreters like everything else).
   ``--start-only`` runs just the start/stop rows against roslaunch.
"""
from __future__ import annotations

import argparse
import compileall
import io
import json
import os
import shutil
import signal
import socket
import statistics
import subprocess
import sys
import tempfile
import threading
import time

import psutil

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, REPO)

sys.path.insert(0, os.path.join(REPO, "bench"))
import ros1  # noqa: E402
from bench_launch import compile_bytecode  # noqa: E402

from orchestra.supervise.output import Screen  # noqa: E402
from orchestra.supervise.process import OutputMode, ProcessSpec, RestartPolicy, State  # noqa: E402
from orchestra.supervise.supervisor import Supervisor  # noqa: E402

NODE_CMD = ("sleep", "1000")


def free_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]


def write_package_xml(pkg: str, name: str) -> None:
    with open(os.path.join(pkg, "package.xml"), "w") as fh:
        fh.write(f"<package format='2'><name>{name}</name><version>0.0.0</version>"
                 "<description>b</description><maintainer email='a@b.c'>a</maintainer>"
                 "<license>BSD</license></package>")


def write_launch(path: str, nodes: list[tuple[str, str, str]]) -> str:
    """A launch file of ``(pkg, type, name)`` nodes; returns ``path``."""
    with open(path, "w") as fh:
        fh.write("<launch>\n")
        for pkg, kind, name in nodes:
            fh.write(f'  <node pkg="{pkg}" type="{kind}" name="{name}"/>\n')
        fh.write("</launch>\n")
    return path


def make_workspace(root: str, n: int) -> str:
    pkg = os.path.join(root, "ws", "benchpkg")
    os.makedirs(os.path.join(pkg, "nodes"))
    write_package_xml(pkg, "benchpkg")
    node = os.path.join(pkg, "nodes", "idle")
    with open(node, "w") as fh:
        fh.write("#!/bin/sh\nexec sleep 1000\n")
    os.chmod(node, 0o755)
    return write_launch(os.path.join(root, "bench.launch"),
                        [("benchpkg", "idle", f"n{i:03d}") for i in range(n)])


def cold_start_and_idle_cpu(n: int, idle: float) -> dict[str, float]:
    with tempfile.TemporaryDirectory() as root:
        launch = make_workspace(root, n)
        env = dict(os.environ, ROS_PACKAGE_PATH=os.path.join(root, "ws"),
                   ROS_HOME=os.path.join(root, "home"), XDG_RUNTIME_DIR=root,
                   ROS_MASTER_URI=f"http://localhost:{free_port()}/")
        env.pop("ROS_LOG_DIR", None)
        # baseline: a fresh interpreter spawning the same n processes
        code = (f"import subprocess,sys\nps=[subprocess.Popen(['sleep','1000']) for _ in range({n})]\n"
                "[p.kill() for p in ps]; [p.wait() for p in ps]")
        t0 = time.perf_counter()
        subprocess.run([sys.executable, "-c", code], check=True)
        baseline = time.perf_counter() - t0

        t0 = time.perf_counter()
        proc = subprocess.Popen([sys.executable, "-m", "orchestra", "launch", launch,
                                 "--no-status", "--disable-title"], env=env,
                                stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        sock_path = os.path.join(root, "orchestra", f"{proc.pid}.sock")
        from orchestra.supervise.status import query
        while True:
            try:
                doc = query(sock_path)
                # the plan's n nodes (/rosout, started with the embedded master, not counted)
                if sum(1 for node in doc["nodes"]
                       if node["state"] == "RUNNING" and node["name"] != "/rosout") == n:
                    break
            except (OSError, ValueError):
                pass
            if proc.poll() is not None:
                raise SystemExit("orchestra launch exited early")
            time.sleep(0.005)
        cold = time.perf_counter() - t0
        ps = psutil.Process(proc.pid)
        time.sleep(0.5)  # let the embedded master settle
        before = ps.cpu_times()
        time.sleep(idle)
        after = ps.cpu_times()
        cpu = max(0.0, (after.user + after.system - before.user - before.system) / idle * 100)
        t0 = time.perf_counter()
        proc.send_signal(signal.SIGINT)
        proc.wait(timeout=60)
        cli_stop = time.perf_counter() - t0
    return {"cold": cold, "cold_baseline": baseline, "idle_cpu": cpu, "cli_stop": cli_stop}


def quiet_screen() -> Screen:
    return Screen(out=io.BytesIO(), err=io.BytesIO(), colour=False)


def spec(name: str, respawn: bool = False) -> ProcessSpec:
    return ProcessSpec(name, NODE_CMD, dict(os.environ), tempfile.gettempdir(), respawn=respawn,
                       output=OutputMode.SCREEN)


def respawn_latency(kills: int) -> dict[str, float]:
    sup = Supervisor([spec("/victim", respawn=True)],
                     RestartPolicy(stable_after=0.05, crash_limit=0), screen=quiet_screen())
    proc = sup.procs[0]
    latencies: list[float] = []

    def killer() -> None:
        try:
            while proc.state != State.RUNNING:
                time.sleep(0.001)
            for _ in range(kills):
                time.sleep(0.1)
                pid = proc.pid
                t0 = time.perf_counter()
                os.kill(pid, signal.SIGKILL)
                while not (proc.pid != pid and proc.state == State.RUNNING):
                    time.sleep(0.0002)
                latencies.append(time.perf_counter() - t0)
        finally:
            sup.loop.call_threadsafe(lambda: sup.request_stop("bench done"))

    thread = threading.Thread(target=killer)
    thread.start()
    sup.run(install_signals=False)
    thread.join()
    baseline = []
    for _ in range(10):
        t0 = time.perf_counter()
        p = subprocess.Popen(NODE_CMD)
        baseline.append(time.perf_counter() - t0)
        p.kill()
        p.wait()
    return {"respawn_median": statistics.median(latencies),
            "respawn_p90": sorted(latencies)[int(len(latencies) * 0.9) - 1],
            "respawn_baseline": statistics.median(baseline)}


def stop_time(n: int) -> dict[str, float]:
    sup = Supervisor([spec(f"/n{i:03d}") for i in range(n)], screen=quiet_screen())
    measured: dict[str, float] = {}

    def stop_when_running() -> None:
        if all(p.state == State.RUNNING for p in sup.procs):
            measured["t0"] = time.perf_counter()
            sup.request_stop("bench")
        else:
            sup.loop.call_later(0.01, stop_when_running)

    sup.loop.call_later(0.01, stop_when_running)
    sup.run(install_signals=False)
    stop = time.perf_counter() - measured["t0"]
    procs = [subprocess.Popen(NODE_CMD, start_new_session=True) for _ in range(n)]
    time.sleep(0.2)
    t0 = time.perf_counter()
    for p in procs:
        os.killpg(p.pid, signal.SIGINT)
    for p in procs:
        p.wait()
    return {"stop": stop, "stop_baseline": time.perf_counter() - t0}


# --- against the real roslaunch ------------------------------------------------------------------

PY_NODE = """#!/usr/bin/python3
# a trivial node: sleeps until SIGINT (or, when stubborn, ignores SIGINT until SIGTERM)
import signal, sys, time
signal.signal(signal.SIGINT, signal.SIG_IGN if "stubborn" in sys.argv[0]
              else (lambda *_: sys.exit(0)))
signal.signal(signal.SIGTERM, lambda *_: sys.exit(0))
while True:
    time.sleep(1000)
"""


NATIVE_NODE = r"""
/* a trivial native node (as roscpp nodes are): sleeps until SIGINT or SIGTERM */
#include <signal.h>
#include <unistd.h>
static void on_signal(int sig) { (void)sig; _exit(0); }
int main(void) {
    signal(SIGINT, on_signal);
    signal(SIGTERM, on_signal);
    for (;;) pause();
}
"""


def build_native_node(root: str) -> bool:
    """Compile NATIVE_NODE as ``rbench/scripts/native`` with the C compiler; False if none."""
    pkg = os.path.join(root, "ws", "rbench", "scripts")
    os.makedirs(pkg, exist_ok=True)
    source = os.path.join(root, "native.c")
    with open(source, "w") as fh:
        fh.write(NATIVE_NODE)
    compiler = next((c for c in ("cc", "gcc", "clang") if shutil.which(c)), None)
    if compiler is None:
        return False
    done = subprocess.run([compiler, "-O2", "-o", os.path.join(pkg, "native"), source],
                          capture_output=True)
    return done.returncode == 0


def make_native_launch(root: str, n: int) -> str:
    return write_launch(os.path.join(root, f"native_{n}.launch"),
                        [("rbench", "native", f"c{i:03d}") for i in range(n)])


def make_py_workspace(root: str, n: int, stubborn: int = 0) -> str:
    """Package ``rbench`` with the python nodes ``sleeper`` and ``stubborn``; a launch of
    ``n`` sleepers plus ``stubborn`` SIGINT-ignoring nodes. Returns the launch file."""
    pkg = os.path.join(root, "ws", "rbench")
    os.makedirs(os.path.join(pkg, "scripts"), exist_ok=True)
    write_package_xml(pkg, "rbench")
    for name in ("sleeper", "stubborn"):
        path = os.path.join(pkg, "scripts", name)
        with open(path, "w") as fh:
            fh.write(PY_NODE)
        os.chmod(path, 0o755)
    return write_launch(os.path.join(root, f"py_{n}_{stubborn}.launch"),
                        [("rbench", "sleeper", f"s{i:03d}") for i in range(n)]
                        + [("rbench", "stubborn", f"x{i:02d}") for i in range(stubborn)])


def is_node_command(argv: list[str]) -> bool:
    """A bench node's command line (not master or rosout; setpriv's until it exec's)."""
    return any("rbench/scripts/" in word for word in argv[:3])


class NodeScan:
    """Finds the launcher's descendants that run a bench node, cheaply enough not to lag.

    The probe runs in its own session, so while 100 interpreters start it gets about 1/100
    of the CPU like everything else. Listing every descendant with psutil and reading every
    one's command line on each 5 ms poll cost several ms of CPU per poll, which then took
    100-300 ms of wall time: the probe saw the last node of a fast launcher well after the
    kernel exec'd it (checked against the kernel's exec timestamps, ``perf record -e
    sched:sched_process_exec``), while for a launcher that spawns slowly the lag was ~15 ms.
    Here each poll lists /proc, reads the parent of new pids only, and the command line of
    descendants not yet known to run a node (exec'd once, they stay so); both launchers are
    probed by the same code.
    """

    def __init__(self, root: int) -> None:
        self.family = {root}
        self.known: set[int] = {root}   # classified pids (descendants or not)
        self.nodes: list[int] = []
        self._matched: set[int] = set()
        self._pending: set[int] = set()   # descendants not (yet) running a node

    def poll(self) -> int:
        """How many node processes have been seen so far (they are not re-checked)."""
        fresh: dict[int, int] = {}
        for entry in os.listdir("/proc"):
            if not entry.isdigit():
                continue
            pid = int(entry)
            if pid in self.known:
                continue
            try:
                with open(f"/proc/{pid}/stat", "rb") as fh:
                    stat = fh.read()
            except OSError:
                continue
            fresh[pid] = int(stat[stat.rfind(b")") + 2:].split(b" ", 2)[1])
        changed = True
        while changed:      # a parent and its child may both be new in one listing
            changed = False
            for pid, ppid in list(fresh.items()):
                if ppid in self.family:
                    self.family.add(pid)
                    self._pending.add(pid)
                    del fresh[pid]
                    changed = True
        self.known.update(self.family)
        self.known.update(fresh)       # not descendants: their ancestry cannot change to ours
        for pid in list(self._pending):
            try:
                with open(f"/proc/{pid}/cmdline", "rb") as fh:
                    argv = fh.read().decode(errors="replace").split("\0")
            except OSError:
                self._pending.discard(pid)
                continue
            if is_node_command(argv):
                self._pending.discard(pid)
                self.nodes.append(pid)
        return len(self.nodes)

    def processes(self) -> list[psutil.Process]:
        found = []
        for pid in self.nodes:
            try:
                found.append(psutil.Process(pid))
            except psutil.NoSuchProcess:
                pass
        return found


def alive(procs: list[psutil.Process]) -> list[psutil.Process]:
    out = []
    for proc in procs:
        try:
            if proc.is_running() and proc.status() != psutil.STATUS_ZOMBIE:
                out.append(proc)
        except psutil.NoSuchProcess:
            pass
    return out


def schedstat(pid: int) -> tuple[float, float]:
    """(ms on a CPU, ms runnable but not running) of all threads of ``pid`` so far.

    From the scheduler's own accounting (``/proc/PID/task/TID/schedstat``): how much CPU a
    process got while the nodes started, and how long it waited for one while it could run.
    """
    ran = waited = 0
    try:
        tids = os.listdir(f"/proc/{pid}/task")
    except OSError:
        return 0.0, 0.0
    for tid in tids:
        try:
            with open(f"/proc/{pid}/task/{tid}/schedstat") as fh:
                fields = fh.read().split()
        except OSError:
            continue
        ran += int(fields[0])
        waited += int(fields[1])
    return ran / 1e6, waited / 1e6


class ExecTrace:
    """The kernel's exec timestamps of every process, recorded by ``perf`` for a while.

    Why: the probe polls from its own session and so gets a turn only as often as any of the
    100 starting interpreters; it saw a fast launcher's last node up to ~200 ms after the
    kernel exec'd it (load ~9), a slow one's within a few ms. ``perf record`` of the
    ``sched:sched_process_exec`` tracepoint on CLOCK_MONOTONIC (``time.monotonic``'s clock)
    gives when each node program really started, the same way for both launchers.
    """

    def __init__(self, root: str) -> None:
        self.data = os.path.join(root, "exec.perf")
        self.proc: subprocess.Popen | None = None
        self.execs: dict[int, list[tuple[float, str]]] = {}
        perf = shutil.which("perf")
        if perf is None:
            self.problem = "perf not found"
            return
        self.proc = subprocess.Popen(
            [perf, "record", "-q", "-a", "-k", "CLOCK_MONOTONIC",
             "-e", "sched:sched_process_exec", "-o", self.data],
            stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
        # recording once the file has its header (perf writes it when it is set up)
        deadline = time.monotonic() + 10
        while time.monotonic() < deadline and self.proc.poll() is None:
            if os.path.exists(self.data) and os.path.getsize(self.data) > 0:
                break
            time.sleep(0.05)
        time.sleep(0.3)
        if self.proc.poll() is not None:
            err = self.proc.stderr.read().decode(errors="replace") if self.proc.stderr else ""
            self.problem = f"perf record failed: {err.strip().splitlines()[-1:] or ['?']}"
            self.proc = None
            return
        self.problem = ""

    def finish(self) -> None:
        """Stop recording and read every exec: pid -> [(monotonic time, filename)]."""
        if self.proc is None:
            return
        self.proc.send_signal(signal.SIGINT)
        self.proc.wait(30)
        out = subprocess.run(["perf", "script", "-i", self.data, "-F", "pid,time,trace"],
                             capture_output=True, text=True).stdout
        for line in out.splitlines():
            head, _, trace = line.partition(": ")
            words = head.split()
            if len(words) < 2 or "filename=" not in trace:
                continue
            filename = trace.split("filename=", 1)[1].split(" pid=")[0]
            self.execs.setdefault(int(words[0]), []).append((float(words[1]), filename))

    def last_node_exec(self, pids: list[int]) -> float | None:
        """When the kernel exec'd the last of ``pids``' node programs (None if one is
        missing from the trace)."""
        times = []
        for pid in pids:
            found = [t for t, filename in self.execs.get(pid, ()) if "rbench/scripts/" in filename]
            if not found:
                return None
            times.append(found[0])
        return max(times) if times else None


#: "floor": a bare python3 that spawns n node commands as orchestra does (own session,
#: setpriv's parent-death signal, stdout/stderr pipes, all at once on threads that stay,
#: since the parent-death signal fires when the forking thread ends) and does nothing else:
#: no master, no launch file. What any launcher written in Python could reach at best.
FLOOR_SPAWNER = """
import os, shutil, subprocess, sys, threading
node, n = os.environ["BENCH_NODE"], int(sys.argv[1])
setpriv = shutil.which("setpriv")
prefix = [setpriv, "--pdeathsig", "KILL", "--"] if setpriv else []
todo = list(range(n))
def spawn():
    while True:
        try:
            i = todo.pop()
        except IndexError:
            break
        subprocess.Popen([*prefix, node, f"__name:=n{i:03d}"], stdout=subprocess.PIPE,
                         stderr=subprocess.PIPE, start_new_session=True)
    threading.Event().wait()
for _ in range(n):
    threading.Thread(target=spawn, daemon=True).start()
threading.Event().wait()
"""


class Launcher:
    """One ``roslaunch`` or ``orchestra launch`` run of a launch file, on its own port; or
    (``floor``) a bare Python spawning ``node_program`` as many times (FLOOR_SPAWNER)."""

    def __init__(self, kind: str, launch: str, root: str, extra: tuple[str, ...] = (),
                 node_program: str = "", n: int = 0) -> None:
        port = free_port()
        uri = f"http://127.0.0.1:{port}/"
        self.kind = kind
        home = os.path.join(root, f"home_{kind}")
        if kind == "floor":   # the program in the environment: the probe reads command lines
            env = dict(os.environ, BENCH_NODE=node_program)
            argv = [sys.executable, "-c", FLOOR_SPAWNER, str(n)]
        elif kind == "roslaunch":
            env = ros1.base_env(ROS_PACKAGE_PATH=os.path.join(root, "ws"), ROS_HOME=home,
                                ROS_MASTER_URI=uri)
            argv = [ros1.tool("roslaunch"), "-p", str(port), *extra, launch]
        else:
            env = dict(os.environ, ROS_PACKAGE_PATH=os.path.join(root, "ws"), ROS_HOME=home,
                       XDG_RUNTIME_DIR=root, ROS_MASTER_URI=uri)
            env.pop("ROS_LOG_DIR", None)
            argv = [sys.executable, "-m", "orchestra", "launch", "--no-status", "--disable-title",
                    *extra, launch]
        self.t0 = time.perf_counter()
        self.t0_monotonic = time.monotonic()
        self.proc = subprocess.Popen(argv, env=env, stdin=subprocess.DEVNULL,
                                     stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                                     start_new_session=True)
        self.ps = psutil.Process(self.proc.pid)
        self.seen: dict[int, psutil.Process] = {}    # node processes
        self.cpu: dict[str, float] = {}   # where the CPU went until all nodes ran (ms)
        self.others: list[psutil.Process] = []       # master, rosout: orphans once it is killed
        self.node_pids: list[int] = []                # those found running the node program

    def wait_running(self, n: int, limit: float = 60.0) -> float:
        """Seconds from Popen until ``n`` node processes run (raises past ``limit``)."""
        scan = NodeScan(self.proc.pid)
        try:
            while True:
                if scan.poll() >= n:
                    took = time.perf_counter() - self.t0
                    self.cpu = self._accounting(scan.nodes, took)
                    self.node_pids = list(scan.nodes)
                    return took
                if self.proc.poll() is not None or time.perf_counter() - self.t0 > limit:
                    raise RuntimeError(f"{self.kind}: {len(scan.nodes)} of {n} nodes after "
                                       f"{time.perf_counter() - self.t0:.1f} s")
                time.sleep(0.005)
        finally:
            for proc in scan.processes():
                self.seen[proc.pid] = proc

    def _accounting(self, nodes: list[int], took: float) -> dict[str, float]:
        """CPU (ms) of the launcher process, of its other processes (master, rosout,
        watchdog) and of the nodes, from its start until every node ran; and the CPU time
        the machine had meanwhile (cores x wall)."""
        launcher, launcher_wait = schedstat(self.proc.pid)
        others = 0.0
        for proc in self.everything():
            if proc.pid not in nodes:
                others += schedstat(proc.pid)[0]
        return {"launcher": launcher, "launcher waiting": launcher_wait, "others": others,
                "nodes": sum(schedstat(pid)[0] for pid in nodes),
                "available": (os.cpu_count() or 1) * took * 1e3}

    def everything(self) -> list[psutil.Process]:
        try:
            return self.ps.children(recursive=True)
        except psutil.NoSuchProcess:
            return []

    def stop(self, limit: float) -> tuple[float, int]:
        """SIGINT the launcher; seconds until it and every node are gone (capped at ``limit``)
        and how many nodes were still running at the cap."""
        nodes = list(self.seen.values())
        t0 = time.perf_counter()
        self.proc.send_signal(signal.SIGINT)
        while time.perf_counter() - t0 < limit:
            if self.proc.poll() is not None and not alive(nodes):
                break
            time.sleep(0.005)
        took = time.perf_counter() - t0
        left = len(alive(nodes))
        self.kill()
        return took, left

    def kill(self) -> None:
        """SIGKILL whatever this run started that still runs (launcher, master, nodes)."""
        procs = self.everything() + list(self.seen.values()) + self.others
        ros1.kill_tree(self.proc.pid)
        for proc in alive(procs):
            try:
                proc.kill()
            except psutil.NoSuchProcess:
                pass
        try:
            self.proc.wait(10)
        except subprocess.TimeoutExpired:
            pass


#: issue 15's targets, by row (orchestra time / roslaunch time)
TARGETS = {"start": "<= 0.25x", "SIGINT to launcher": "<= 0.15x"}


def real_roslaunch_comparison(n: int, quick: bool, start_only: bool = False) -> list:
    """Rows (what, orchestra, roslaunch, note) for section 5 (``start_only``: the start and
    SIGINT rows only)."""
    rows: list = []
    with tempfile.TemporaryDirectory() as root:
        trace = ExecTrace(root)
        traced: list[tuple[str, str, float, list[int]]] = []   # what, kind, t0, node pids
        launch = make_py_workspace(root, n)
        launches = [("python", launch)]
        programs = {"python": os.path.join(root, "ws", "rbench", "scripts", "sleeper")}
        if build_native_node(root):
            launches.append(("native", make_native_launch(root, n)))
            programs["native"] = os.path.join(root, "ws", "rbench", "scripts", "native")
        else:
            rows.append([f"start {n} native nodes", "orchestra", None,
                         "skipped: no C compiler (cc) to build the native node"])
        # start, then SIGINT stop; interleaved, median of `repeat` runs each
        repeat = 3 if quick else 5
        for what, file in launches:
            times: dict[str, dict[str, list[float]]] = {}
            cpu: dict[str, list[dict[str, float]]] = {}
            floor: list[float] = []
            for _ in range(repeat):
                for kind in ("orchestra", "roslaunch", "floor"):
                    run = Launcher(kind, file, root, node_program=programs[what], n=n)
                    try:
                        started = run.wait_running(n)
                        traced.append((what, kind, run.t0_monotonic, run.node_pids))
                        if kind == "floor":
                            floor.append(started)
                            continue
                        cpu.setdefault(kind, []).append(run.cpu)
                        time.sleep(1.0)  # let the launcher settle (registrations, rosout)
                        took, left = run.stop(40)
                    finally:
                        run.kill()
                    mine = times.setdefault(kind, {"start": [], "stop": []})
                    mine["start"].append(started)
                    mine["stop"].append(took)
                    if left:
                        rows.append([f"SIGINT with {what} nodes", kind, None, f"{left} left"])
            for kind, figures in times.items():
                rows.append([f"start {n} {what} nodes until all run (median of {repeat})",
                             kind, statistics.median(figures["start"])])
                rows.append([f"SIGINT to launcher -> launcher and {n} {what} nodes gone "
                             f"(median of {repeat})", kind, statistics.median(figures["stop"])])
            label = f"  floor: a bare python3 spawning the same {n} {what} nodes, until all run"
            rows.append([label, "orchestra", statistics.median(floor),
                         "the floor in the orchestra column (FLOOR_SPAWNER)"])
            rows.append([label, "roslaunch", statistics.median(times["roslaunch"]["start"])])
            for kind, runs in cpu.items():
                med = {key: statistics.median(r[key] for r in runs) for key in runs[0]}
                rows.append([f"  CPU until all {what} nodes ran (ms, medians)", kind, None,
                             f"launcher {med['launcher']:.0f} (its threads runnable, not running: "
                             f"{med['launcher waiting']:.0f}), master/rosout/helpers "
                             f"{med['others']:.0f}, nodes {med['nodes']:.0f}, "
                             f"of {med['available']:.0f} on {os.cpu_count()} cores"])
        trace.finish()
        rows += kernel_start_rows(trace, traced, n)
        if start_only:
            return merge_rows(rows)
        # SIGINT-ignoring nodes: default escalation, then --sigint-timeout
        stubborn = 3
        launch_x = make_py_workspace(root, 10, stubborn)
        settings = [((), "default timeouts")] if not quick else []
        settings.append((("--sigint-timeout", "2", "--sigterm-timeout", "1"),
                         "--sigint-timeout 2 --sigterm-timeout 1"))
        for extra, label in settings:
            for kind in ("orchestra", "roslaunch"):
                run = Launcher(kind, launch_x, root, extra)
                try:
                    run.wait_running(10 + stubborn)
                    time.sleep(1.0)
                    took, left = run.stop(40)
                    rows.append([f"stop 10 nodes + {stubborn} ignoring SIGINT, {label}", kind,
                                 took, f"{left} left at 40 s cap" if left else ""])
                finally:
                    run.kill()
        # the launcher SIGKILLed: what keeps running
        for kind in ("orchestra", "roslaunch"):
            run = Launcher(kind, launch, root)
            try:
                run.wait_running(n)
                time.sleep(1.0)
                run.others = [p for p in run.everything() if p.pid not in run.seen]
                os.kill(run.proc.pid, signal.SIGKILL)
                run.proc.wait(10)
                time.sleep(2.0)
                orphans = len(alive(list(run.seen.values())))
                other_left = len(alive(run.others))
                rows.append([f"launcher SIGKILLed: nodes still running after 2 s (of {n})", kind,
                             orphans, f"+{other_left} master/rosout processes"])
            finally:
                run.kill()
    return merge_rows(rows)


def kernel_start_rows(trace: ExecTrace, traced: list[tuple[str, str, float, list[int]]],
                      n: int) -> list:
    """The start rows again, from the kernel's exec timestamps: launcher Popen until the
    kernel exec'd its last node program; medians and the per-round ratios."""
    if trace.problem:
        return [[f"start {n} nodes by the kernel's exec timestamps", "orchestra", None,
                 f"skipped: {trace.problem}"]]
    rows: list = []
    by: dict[tuple[str, str], list[float]] = {}
    missing = False
    for what, kind, t0, pids in traced:
        last = trace.last_node_exec(pids)
        if last is None:
            missing = True
            continue
        by.setdefault((what, kind), []).append(last - t0)
    if missing:
        rows.append([f"start {n} nodes by the kernel's exec timestamps", "orchestra", None,
                     "an exec missing from the trace: those runs left out"])
    for what in dict.fromkeys(w for w, _ in by):
        ours, theirs = by.get((what, "orchestra"), []), by.get((what, "roslaunch"), [])
        if not ours or not theirs:
            continue
        label = (f"start {n} {what} nodes until the kernel exec'd the last "
                 f"(median of {min(len(ours), len(theirs))})")
        per_round = sorted(a / b for a, b in zip(ours, theirs, strict=False))
        rows.append([label, "orchestra", statistics.median(ours),
                     f"per round {statistics.median(per_round):.2f}x "
                     f"[{per_round[0]:.2f}-{per_round[-1]:.2f}]"])
        rows.append([label, "roslaunch", statistics.median(theirs)])
        floor = by.get((what, "floor"), [])
        if floor:
            floor_label = f"  floor ({what} nodes, bare python3 spawner), the same way"
            rows.append([floor_label, "orchestra", statistics.median(floor),
                         "the floor in the orchestra column"])
            rows.append([floor_label, "roslaunch", statistics.median(theirs)])
    return rows


def merge_rows(rows: list) -> list:
    """One (what, orchestra, roslaunch, notes) row per measure."""
    merged: dict = {}
    for what, kind, value, *note in rows:
        entry = merged.setdefault(what, {"note": []})
        entry[kind] = value
        if note and note[0]:
            entry["note"].append(f"{kind}: {note[0]}")
    return [(what, e.get("orchestra"), e.get("roslaunch"), "; ".join(e["note"]))
            for what, e in merged.items()]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--nodes", type=int, default=100)
    parser.add_argument("--kills", type=int, default=30)
    parser.add_argument("--idle", type=float, default=5.0)
    parser.add_argument("--quick", action="store_true",
                        help="fewer kills, shorter idle window, no default-timeout escalation")
    parser.add_argument("--json", action="store_true", help="print the figures as JSON")
    parser.add_argument("--start-only", action="store_true",
                        help="only the start and SIGINT rows against roslaunch")
    args = parser.parse_args()
    # started in the background by a non-interactive shell (`cmd &`), this process ignores
    # SIGINT and every node it starts would inherit that: the SIGINT rows would wait on nodes
    # that cannot hear it. A handled signal is reset to its default in an exec'd child.
    signal.signal(signal.SIGINT, signal.default_int_handler)
    if args.quick:
        args.kills, args.idle = min(args.kills, 10), min(args.idle, 2.0)
    # orchestra byte-compiled as an install leaves it (Debian's roslaunch is): with
    # PYTHONDONTWRITEBYTECODE set, as on the development machine, every launch compiled its
    # modules from source (~30 ms of CPU before the first node)
    compile_bytecode()
    for package in ("rosout",):    # orchestra's own core node, started by every launch
        compileall.compile_dir(os.path.join(REPO, "packages", package), quiet=2)
    if not args.json:
        print(ros1.load_average())
    figures: dict[str, float] = {}
    if not args.start_only:
        figures.update(cold_start_and_idle_cpu(args.nodes, args.idle))
        figures.update(respawn_latency(args.kills))
        figures.update(stop_time(args.nodes))
    real_rows = []
    if ros1.tool("roslaunch") is None:
        if not args.json:
            ros1.skip("the real roslaunch comparison", "roslaunch (ROS 1)")
    else:
        real_rows = real_roslaunch_comparison(args.nodes, args.quick, args.start_only)
    if args.json:
        figures["ros1"] = [{"what": w, "orchestra": o, "roslaunch": r, "note": note}
                           for w, o, r, note in real_rows]
        print(json.dumps(figures, indent=1))
        return
    n = args.nodes
    rows = [] if args.start_only else [
        (f"cold start, {n} nodes RUNNING (CLI, embedded master)", figures["cold"],
         figures["cold_baseline"], "-"),
        ("crash -> respawn latency, median", figures["respawn_median"],
         figures["respawn_baseline"], "< 0.020 s"),
        ("crash -> respawn latency, p90", figures["respawn_p90"], figures["respawn_baseline"], "-"),
        (f"stop {n} well-behaved nodes (Supervisor)", figures["stop"],
         figures["stop_baseline"], "< 0.500 s"),
        (f"stop {n} nodes, SIGINT to orchestra -> exit (CLI)", figures["cli_stop"],
         figures["stop_baseline"], "-"),
    ]
    if rows:
        print(f"{'measure':<52} {'orchestra':>10} {'baseline':>10} {'ratio':>7}  target")
        for label, value, base, target in rows:
            print(f"{label:<52} {value:>9.3f}s {base:>9.3f}s {value / base:>7.2f}  {target}")
        print(f"{'supervisor CPU, ' + str(n) + ' idle nodes (% of one core)':<52} "
              f"{figures['idle_cpu']:>9.2f}% {'':>10} {'':>7}  < 1 %")
    if real_rows:
        print(f"\n{'against real roslaunch (same launch file)':<80} {'orchestra':>10} "
              f"{'roslaunch':>10} {'ratio':>7}  target")
        for what, ours, theirs, note in real_rows:
            if ours is None and theirs is None:     # notes only: one line per launcher
                print(what)
                for part in note.split("; "):
                    print(f"    {part}")
            elif ours is None or theirs is None:
                print(f"{what:<80} {note}")
            elif isinstance(ours, int):
                print(f"{what:<80} {ours:>10} {theirs:>10} {'':>7}  {note}")
            else:
                target = next((t for key, t in TARGETS.items() if what.startswith(key)), "")
                print(f"{what:<80} {ours:>9.2f}s {theirs:>9.2f}s {ours / theirs:>6.2f}x  "
                      f"{target}{'  ' + note if note else ''}")
        print("ratio = orchestra time / roslaunch time (lower: orchestra faster). Python nodes:\n"
              "  both launchers pay 100 /usr/bin/python3 start-ups competing for the same cores\n"
              "  (a floor shared by both sides); native nodes: what the launchers themselves cost.")
    print(ros1.load_average())


if __name__ == "__main__":
    main()
