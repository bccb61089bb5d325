"""Master throughput: orchestra's master against the real rosmaster, both as processes.

Plain Python, no pytest. Both masters run as separate processes started the same way and
pinned to the same CPU (``orchestra core -p PORT --no-rosout`` and ``rosmaster --core -p
PORT``), and are filled and called by the same client code in this process
(``xmlrpc.client``, like rospy): per-call rates of getParam/setParam, getParam('/') with
1,000 params, getSystemState with 1,000 registrations, and the time of 1,000 sequential
registerPublisher calls and of one multicall of 1,000 setParam. Every measurement is taken
``--rounds`` times, interleaved between the two masters; the tables show medians. Skipped
with a message when /usr/bin/rosmaster is missing (orchestra's figures still print).

Usage: ``python bench/bench_master.py [--quick] [--seconds 1.0] [--rounds 5] [--cpu N]``
"""
from __future__ import annotations

import argparse
import os
import shutil
import socket
import statistics
import subprocess
import sys
import time
import xmlrpc.client
from collections.abc import Callable

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import ros1  # noqa: E402

PIN: list[str] = []


def rate(fn, seconds: float) -> float:
    """Calls per second of ``fn`` over about ``seconds`` (after a short warm-up)."""
    for _ in range(20):
        fn()
    calls = 0
    start = time.perf_counter()
    deadline = start + seconds
    while True:
        for _ in range(50):
            fn()
        calls += 50
        now = time.perf_counter()
        if now >= deadline:
            return calls / (now - start)


def free_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]


class MasterProcess:
    """A master as its own process on a free port; stop() kills it and its children."""

    def __init__(self, argv: list[str], env: dict[str, str]) -> None:
        self.port = free_port()
        self.uri = f"http://127.0.0.1:{self.port}/"
        env = {**env, "ROS_MASTER_URI": self.uri}
        self.proc = subprocess.Popen([*PIN, *argv, "-p", str(self.port)], env=env,
                                     stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                                     start_new_session=True)
        deadline = time.monotonic() + 30
        while True:
            try:
                xmlrpc.client.ServerProxy(self.uri).getSystemState("/bench")
                return
            except OSError:
                if self.proc.poll() is not None or time.monotonic() > deadline:
                    self.stop()
                    raise RuntimeError(f"{argv[0]} did not come up") from None
                time.sleep(0.05)

    def stop(self) -> None:
        ros1.kill_tree(self.proc.pid)
        self.proc.wait(10)


def orchestra_master() -> MasterProcess:
    return MasterProcess([sys.executable, "-m", "orchestra", "core", "--no-rosout"],
                         dict(os.environ))


def real_rosmaster() -> MasterProcess:
    return MasterProcess([ros1.tool("rosmaster") or "rosmaster", "--core"], ros1.base_env())


def populate(param_uri: str, graph_uri: str, n: int) -> None:
    """1,000 params on one master, ``n`` registrations (pub/sub/service) on the other."""
    m = xmlrpc.client.ServerProxy(param_uri)
    g = xmlrpc.client.ServerProxy(graph_uri)
    m.setParam("/bench", "/robot/gain", 1.5)
    multi = xmlrpc.client.MultiCall(m)
    for i in range(1000):
        multi.setParam("/bench", f"/ns{i % 10}/node{i}/param", i)
    multi()
    for i in range(n):
        node = f"/node{i}"
        api = f"http://127.0.0.1:{20000 + i}/"
        kind = i % 3
        if kind == 0:
            g.registerPublisher(node, f"/topic{i % 100}", "std_msgs/String", api)
        elif kind == 1:
            g.registerSubscriber(node, f"/topic{i % 100}_in", "std_msgs/String", api)
        else:
            g.registerService(node, f"/srv{i}", f"rosrpc://127.0.0.1:{30000 + i}", api)
    state = g.getSystemState("/b")[2]
    assert sum(len(ids) for section in state for _, ids in section) == n


def register_publishers(uri: str, n: int, round_no: int) -> float:
    """Seconds for ``n`` sequential registerPublisher calls (new topics every round)."""
    g = xmlrpc.client.ServerProxy(uri)
    start = time.perf_counter()
    for i in range(n):
        g.registerPublisher(f"/pub{i}", f"/r{round_no}/topic{i}", "std_msgs/String",
                            f"http://127.0.0.1:{40000 + i % 20000}/")
    return time.perf_counter() - start


def multicall_set(uri: str, n: int, round_no: int) -> float:
    """Seconds for one system.multicall of ``n`` setParam calls."""
    multi = xmlrpc.client.MultiCall(xmlrpc.client.ServerProxy(uri))
    for i in range(n):
        multi.setParam("/bench", f"/multi/r{round_no}/p{i}", i)
    start = time.perf_counter()
    results = list(multi())
    took = time.perf_counter() - start
    assert len(results) == n
    return took


def rate_cases(param_uri: str, graph_uri: str, n: int) -> list[tuple[str, Callable[[], object]]]:
    """The calls measured on any master, through one client (xmlrpc.client, like rospy)."""
    m = xmlrpc.client.ServerProxy(param_uri)
    g = xmlrpc.client.ServerProxy(graph_uri)
    counter = iter(range(10 ** 9))
    return [
        ("getParam (leaf), calls/s", lambda: m.getParam("/bench", "/robot/gain")),
        ("setParam (leaf), calls/s", lambda: m.setParam("/bench", "/robot/gain", next(counter))),
        ("getParam('/') with 1,000 params, calls/s", lambda: m.getParam("/b", "/")),
        (f"getSystemState with {n:,} registrations, calls/s", lambda: g.getSystemState("/b")),
    ]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=None,
                        help="time per rate measurement (default 1.0; 0.3 with --quick)")
    parser.add_argument("--rounds", type=int, default=5,
                        help="measure everything this many times, interleaved; medians")
    parser.add_argument("--registrations", type=int, default=1000)
    parser.add_argument("--cpu", type=int, default=None,
                        help="pin both masters to this CPU (default: the last; -1: no pinning)")
    parser.add_argument("--quick", action="store_true", help="shorter measurements")
    args = parser.parse_args()
    seconds = args.seconds or (0.3 if args.quick else 1.0)
    n = args.registrations
    cpu = (os.cpu_count() or 1) - 1 if args.cpu is None else args.cpu
    if cpu >= 0 and shutil.which("taskset"):
        PIN[:] = ["taskset", "-c", str(cpu)]
    print(ros1.load_average())
    sides: dict[str, list[MasterProcess]] = {}
    try:
        sides["orchestra"] = [orchestra_master(), orchestra_master()]
        if ros1.tool("rosmaster") is None:
            ros1.skip("the real rosmaster", "rosmaster (ROS 1)")
        else:
            sides["rosmaster"] = [real_rosmaster(), real_rosmaster()]
        for params, graph in sides.values():
            populate(params.uri, graph.uri, n)
        names = [name for name, _ in rate_cases("http://x/", "http://x/", n)]
        names += ["1,000 registerPublisher, sequential, ms", "multicall of 1,000 setParam, ms"]
        results: dict[str, list[list[float]]] = {side: [[] for _ in names] for side in sides}
        for round_no in range(args.rounds):
            for side, (params, graph) in sides.items():   # interleaved
                cases = rate_cases(params.uri, graph.uri, n)
                for i, (_, fn) in enumerate(cases):
                    results[side][i].append(rate(fn, seconds))
                results[side][len(cases)].append(
                    register_publishers(graph.uri, 1000, round_no) * 1e3)
                results[side][len(cases) + 1].append(multicall_set(params.uri, 1000, round_no) * 1e3)
    finally:
        for masters in sides.values():
            for master in masters:
                master.stop()

    width = max(len(name) for name in names)
    med = {side: [statistics.median(v) for v in values] for side, values in results.items()}
    print(f"\n{'median of ' + str(args.rounds) + ' rounds':<{width}}  {'orchestra':>10}  "
          f"{'rosmaster':>10}  {'ratio':>6}")
    for i, name in enumerate(names):
        ours = med["orchestra"][i]
        if "rosmaster" in med:
            theirs = med["rosmaster"][i]
            print(f"{name:<{width}}  {ours:10.1f}  {theirs:10.1f}  {ours / theirs:5.2f}x")
        else:
            print(f"{name:<{width}}  {ours:10.1f}")
    print("ratio = orchestra / rosmaster (calls/s rows: higher is faster; ms rows: lower is "
          "faster)")
    print(ros1.load_average())


if __name__ == "__main__":
    main()
