"""Process-supervision figures, each with a baseline measured in the same run.

    python bench/bench_supervise.py [--nodes 100] [--kills 30] [--idle 5]

1. cold start: ``orchestra launch`` of N nodes (embedded master) until its status socket
   reports all N RUNNING; baseline: a fresh Python that Popen's the same N processes.
2. crash -> respawn latency (respawn_delay=0): SIGKILL a node, time until its replacement is
   RUNNING; baseline: one bare Popen of the same command. Target: median < 20 ms.
3. stop of N well-behaved nodes: request_stop -> every node reaped; baseline: SIGINT + wait
   on N bare Popen'd processes. Target: < 0.5 s.
4. supervisor CPU with N idle nodes over a window (orchestra process, embedded master
   included), in % of one core. Target: < 1 %.
"""
from __future__ import annotations

import argparse
import io
import json
import os
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

from orchestra.supervise.output import Screen  # noqa: E402
from orchestra.supervise.process import OutputMode, ProcessSpec, RestartPolicy, State  # noqa: E402
from orchestra.supervise.supervisor import Supervisor  # noqa: E402

NODE_CMD = ("sleep", "1000")


def free_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]


def make_workspace(root: str, n: int) -> str:
    pkg = os.path.join(root, "ws", "benchpkg")
    os.makedirs(os.path.join(pkg, "nodes"))
    with open(os.path.join(pkg, "package.xml"), "w") as fh:
        fh.write("<package format='2'><name>benchpkg</name><version>0.0.0</version>"
                 "<description>b</description><maintainer email='a@b.c'>a</maintainer>"
                 "<license>BSD</license></package>")
    node = os.path.join(pkg, "nodes", "idle")
    with open(node, "w") as fh:
        fh.write("#!/bin/sh\nexec sleep 1000\n")
    os.chmod(node, 0o755)
    launch = os.path.join(root, "bench.launch")
    with open(launch, "w") as fh:
        fh.write("<launch>\n")
        for i in range(n):
            fh.write(f'  <node pkg="benchpkg" type="idle" name="n{i:03d}"/>\n')
        fh.write("</launch>\n")
    return launch


def cold_start_and_idle_cpu(n: int, idle: float) -> dict[str, float]:
    with tempfile.TemporaryDirectory() as root:
        launch = make_workspace(root, n)
        env = dict(os.environ, ROS_PACKAGE_PATH=os.path.join(root, "ws"),
                   ROS_HOME=os.path.join(root, "home"), XDG_RUNTIME_DIR=root,
                   ROS_MASTER_URI=f"http://localhost:{free_port()}/")
        env.pop("ROS_LOG_DIR", None)
        # baseline: a fresh interpreter spawning the same n processes
        code = ("import subprocess,sys\nps=[subprocess.Popen(['sleep','1000']) for _ in range(%d)]\n"
                "[p.kill() for p in ps]; [p.wait() for p in ps]" % n)
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
        cpu = (after.user + after.system - before.user - before.system) / idle * 100
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


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--nodes", type=int, default=100)
    parser.add_argument("--kills", type=int, default=30)
    parser.add_argument("--idle", type=float, default=5.0)
    parser.add_argument("--json", action="store_true", help="print the figures as JSON")
    args = parser.parse_args()
    figures: dict[str, float] = {}
    figures.update(cold_start_and_idle_cpu(args.nodes, args.idle))
    figures.update(respawn_latency(args.kills))
    figures.update(stop_time(args.nodes))
    if args.json:
        print(json.dumps(figures, indent=1))
        return
    n = args.nodes
    rows = [
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
    print(f"{'measure':<52} {'orchestra':>10} {'baseline':>10} {'ratio':>7}  target")
    for label, value, base, target in rows:
        print(f"{label:<52} {value:>9.3f}s {base:>9.3f}s {value / base:>7.2f}  {target}")
    print(f"{'supervisor CPU, ' + str(n) + ' idle nodes (% of one core)':<52} "
          f"{figures['idle_cpu']:>9.2f}% {'':>10} {'':>7}  < 1 %")


if __name__ == "__main__":
    main()
