"""Remote-machine start-up: N nodes on one remote host vs the same N nodes run locally.

    sudo python bench/bench_remote.py [--nodes 50] [--runs 5]

Needs root, ``ip netns`` and sshd (tests/node_fixtures/netns_ssh.py builds the two-namespace
testbed: a private 10.213.N.0/24 subnet, a real sshd in one namespace, orchestra in the
other). Each run is ``orchestra launch`` (embedded master, rosout) of a launch file of N
trivial ``#!python3`` nodes that write a marker and sleep -- all local, or all on the remote
machine -- timed from the launch's Popen until every node's marker exists, then stopped with
SIGINT (and waited for until nothing is left in either namespace). Local and remote runs are
interleaved; medians are reported with their ratio (target: remote < 2x local).

The remote figure includes what only a remote launch pays: the ssh master connection, the
preflight check on the machine, one multiplexed ssh session and one agent per node. The
reference roslaunch is not run: its remote launch needs paramiko and a roslaunch on the
remote side, neither of which this testbed provides.
"""
from __future__ import annotations

import argparse
import os
import signal
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO / "tests" / "node_fixtures"))
import netns_ssh  # noqa: E402

NODE = """#!PYTHON
import os, sys, time
name = [a[8:] for a in sys.argv if a.startswith("__name:=")][0]
open(os.path.join(os.environ["MARKS"], name), "w").close()
try:
    time.sleep(1000)
except KeyboardInterrupt:
    pass
"""


def workspace(root: Path) -> Path:
    pkg = root / "ws" / "benchpkg"
    pkg.mkdir(parents=True)
    (pkg / "package.xml").write_text(
        "<package format='2'><name>benchpkg</name><version>0.0.0</version><description>b"
        "</description><maintainer email='a@b.c'>a</maintainer><license>BSD</license>"
        "</package>")
    (pkg / "sleeper").write_text(NODE.replace("PYTHON", sys.executable))
    (pkg / "sleeper").chmod(0o755)
    return root / "ws"


def launch_file(root: Path, bed: netns_ssh.Testbed, n: int, remote: bool) -> Path:
    machine = ' machine="far"' if remote else ""
    nodes = "\n".join(f'  <node pkg="benchpkg" type="sleeper" name="n{i}"{machine}/>'
                      for i in range(n))
    path = root / ("remote.launch" if remote else "local.launch")
    path.write_text(f'<launch>\n  <machine name="far" address="{bed.remote_ip}" '
                    f'env-loader="{bed.loader}"/>\n{nodes}\n</launch>\n')
    return path


def one_run(bed: netns_ssh.Testbed, launch: Path, env: dict[str, str], marks: Path,
            n: int) -> float:
    for old in marks.iterdir():
        old.unlink()
    start = time.perf_counter()
    proc = bed.popen_local([sys.executable, "-m", "orchestra", "launch", str(launch),
                            "--no-status", "--disable-title"], env=env,
                           stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    deadline = time.monotonic() + 120
    while len(os.listdir(marks)) < n:
        if proc.poll() is not None or time.monotonic() > deadline:
            raise RuntimeError(f"launch ended or hung (exit {proc.returncode})")
        time.sleep(0.005)
    elapsed = time.perf_counter() - start
    proc.send_signal(signal.SIGINT)
    proc.wait(60)
    deadline = time.monotonic() + 30
    while any(pid != bed.sshd.pid for ns in (bed.local_ns, bed.remote_ns)
              for pid in bed.pids_in(ns)) and time.monotonic() < deadline:
        time.sleep(0.05)
    return elapsed


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--nodes", type=int, default=50)
    parser.add_argument("--runs", type=int, default=5)
    args = parser.parse_args()
    why = netns_ssh.unavailable()
    if why:
        print(f"skipped: {why}")
        return 0
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        ws = workspace(root)
        marks = root / "marks"
        marks.mkdir()
        with netns_ssh.Testbed(root) as bed:
            bed.loader = bed.env_loader(root / "loader.sh", {
                "ROS_PACKAGE_PATH": str(ws), "ROS_HOME": str(root / "rhome"),
                "MARKS": str(marks)})
            env = {**os.environ, "ROS_PACKAGE_PATH": str(ws), "ROS_HOME": str(root / "home"),
                   "XDG_RUNTIME_DIR": str(root), "ROS_MASTER_URI": "http://localhost:11311/",
                   "ORCHESTRA_SSH_CONFIG": str(bed.ssh_config), "MARKS": str(marks),
                   "PYTHONPATH": str(REPO)}
            env.pop("ROS_LOG_DIR", None)
            files = {kind: launch_file(root, bed, args.nodes, kind == "remote")
                     for kind in ("local", "remote")}
            times: dict[str, list[float]] = {"local": [], "remote": []}
            for _ in range(args.runs):
                for kind in ("local", "remote"):
                    times[kind].append(one_run(bed, files[kind], env, marks, args.nodes))
    local, remote = (statistics.median(times[k]) for k in ("local", "remote"))
    print(f"{args.nodes} nodes, {args.runs} interleaved runs each, medians "
          "(launch until every node runs):")
    print(f"  local : {local:.2f} s   (runs: {', '.join(f'{t:.2f}' for t in times['local'])})")
    print(f"  remote: {remote:.2f} s   (runs: {', '.join(f'{t:.2f}' for t in times['remote'])})")
    print(f"  ratio remote/local: {remote / local:.2f} (target < 2)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
