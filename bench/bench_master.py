"""Master throughput: parameter calls per second and getSystemState at 1,000 registrations.

Plain Python, no pytest. Every figure is measured in this run next to a baseline measured the
same way in the same run, so ratios stay meaningful on a busy machine:

- baseline "stdlib no-op": a threaded stdlib SimpleXMLRPCServer speaking HTTP/1.0 (one TCP
  connection per call, like rosmaster's server) whose method returns [1, "", 0] at once;
  this is the cost of an XML-RPC round trip with no master logic at all.
- baseline "keep-alive no-op": the same no-op method on orchestra's server class, to separate
  the transport gain from the master's own cost.

- the real ROS 1 rosmaster (Debian's, ``rosmaster --core -p PORT`` on a free port), filled
  and called by the same client code as orchestra's master: the baseline users care about.
  Skipped with a message when /usr/bin/rosmaster is missing.

Usage: ``python bench/bench_master.py [--quick] [--seconds 1.0]``
"""
from __future__ import annotations

import argparse
import os
import socket
import socketserver
import subprocess
import sys
import threading
import time
import xmlrpc.client
from xmlrpc.server import SimpleXMLRPCServer

from orchestra.master import start_master, upload_params
from orchestra.master.server import ThreadedXMLRPCServer

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import ros1  # noqa: E402


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


class _StdlibThreaded(socketserver.ThreadingMixIn, SimpleXMLRPCServer):
    daemon_threads = True


def _serve(server) -> threading.Thread:
    thread = threading.Thread(target=server.serve_forever, kwargs={"poll_interval": 0.1},
                              daemon=True)
    thread.start()
    return thread


def _noop(caller_id, key):
    return [1, "", 0]


def free_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]


class RealRosmaster:
    """``rosmaster --core -p PORT`` (ROS 1) on a free port; stop() kills it and its children."""

    def __init__(self) -> None:
        self.port = free_port()
        self.uri = f"http://127.0.0.1:{self.port}/"
        self.proc = subprocess.Popen([ros1.tool("rosmaster"), "--core", "-p", str(self.port)],
                                     env=ros1.base_env(ROS_MASTER_URI=self.uri),
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
                    raise RuntimeError("rosmaster did not come up") from None
                time.sleep(0.05)

    def stop(self) -> None:
        ros1.kill_tree(self.proc.pid)
        self.proc.wait(10)


def populate(param_uri: str, graph_uri: str, n: int) -> tuple[float, float]:
    """1,000 params on one master, ``n`` registrations on the other; seconds for each."""
    m = xmlrpc.client.ServerProxy(param_uri)
    g = xmlrpc.client.ServerProxy(graph_uri)
    m.setParam("/bench", "/robot/gain", 1.5)
    params = {f"/ns{i % 10}/node{i}/param": i for i in range(1000)}
    start = time.perf_counter()
    upload_params(param_uri, params, ["/ns0"])
    upload_s = time.perf_counter() - start
    start = time.perf_counter()
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
    register_s = time.perf_counter() - start
    state = g.getSystemState("/b")[2]
    assert sum(len(ids) for section in state for _, ids in section) == n
    return upload_s, register_s


def client_cases(param_uri: str, graph_uri: str, n: int) -> list:
    """The calls measured on any master, through one client (xmlrpc.client, like rospy)."""
    m = xmlrpc.client.ServerProxy(param_uri)
    g = xmlrpc.client.ServerProxy(graph_uri)
    counter = iter(range(10 ** 9))
    return [
        ("getParam (leaf)", lambda: m.getParam("/bench", "/robot/gain")),
        ("setParam (leaf)", lambda: m.setParam("/bench", "/robot/gain", next(counter))),
        ("getParam('/') with 1,000 params", lambda: m.getParam("/b", "/")),
        (f"getSystemState with {n:,} registrations", lambda: g.getSystemState("/b")),
    ]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=None,
                        help="time per measurement (default 1.0; 0.3 with --quick)")
    parser.add_argument("--rounds", type=int, default=3,
                        help="measure everything this many times, interleaved; keep the best "
                             "(the machine is shared: the best round is the least disturbed)")
    parser.add_argument("--registrations", type=int, default=1000)
    parser.add_argument("--quick", action="store_true", help="shorter measurements")
    args = parser.parse_args()
    seconds = args.seconds or (0.3 if args.quick else 1.0)
    n = args.registrations
    print(ros1.load_average())

    stdlib = _StdlibThreaded(("127.0.0.1", 0), logRequests=False)
    stdlib.register_function(_noop, "noop")
    _serve(stdlib)
    keepalive = ThreadedXMLRPCServer(("127.0.0.1", 0))
    keepalive.register_function(_noop, "noop")
    _serve(keepalive)
    master = start_master(port=0)   # parameters and a leaf to read/write
    graph = start_master(port=0)    # 1,000 registrations
    real: list[RealRosmaster] = []
    try:
        if ros1.tool("rosmaster") is None:
            ros1.skip("the real rosmaster", "rosmaster (ROS 1)")
        else:
            real = [RealRosmaster(), RealRosmaster()]
        p_std = xmlrpc.client.ServerProxy(f"http://127.0.0.1:{stdlib.server_address[1]}/")
        p_ka = xmlrpc.client.ServerProxy(f"http://127.0.0.1:{keepalive.server_address[1]}/")
        upload_s, register_s = populate(master.uri, graph.uri, n)
        if real:
            r_upload_s, r_register_s = populate(real[0].uri, real[1].uri, n)

        # the master's own share of a big reply: dispatch plus XML encoding, without the
        # client's (pure-Python) XML parsing that dominates the round trip
        def server_side(api, method, *call_args):
            return lambda: xmlrpc.client.dumps((api._dispatch(method, call_args),),
                                               methodresponse=True)
        ours = client_cases(master.uri, graph.uri, n)
        cases = [
            ("stdlib no-op (HTTP/1.0, rosmaster transport)", lambda: p_std.noop("/b", "/k")),
            ("orchestra server no-op (keep-alive)", lambda: p_ka.noop("/b", "/k")),
            *ours[:3],
            ("  same, server side only (dispatch + encode)",
             server_side(master.api, "getParam", "/b", "/")),
            ours[3],
            ("  same, server side only (dispatch + encode)",
             server_side(graph.api, "getSystemState", "/b")),
        ]
        theirs = client_cases(real[0].uri, real[1].uri, n) if real else []
        best = [0.0] * len(cases)
        best_real = [0.0] * len(theirs)
        for _ in range(args.rounds):
            for i, (_, fn) in enumerate(cases):
                best[i] = max(best[i], rate(fn, seconds / args.rounds))
            for i, (_, fn) in enumerate(theirs):
                best_real[i] = max(best_real[i], rate(fn, seconds / args.rounds))
    finally:
        for server in (stdlib, keepalive):
            server.shutdown()
            server.server_close()
        master.shutdown()
        graph.shutdown()
        for proc in real:
            proc.stop()

    base = best[0]
    width = max(len(name) for name, _ in cases)
    print(f"{'measurement':<{width}}  {'calls/s':>9}  {'ms/call':>8}  {'x baseline':>10}")
    for (name, _), value in zip(cases, best, strict=False):
        print(f"{name:<{width}}  {value:9.0f}  {1000 / value:8.3f}  {value / base:10.2f}")
    print(f"upload_params: 1,000 params + 1 clear in one multicall: {upload_s * 1000:.1f} ms")
    print(f"{n:,} registrations (pub/sub/service mix), sequential: {register_s * 1000:.0f} ms "
          f"({n / register_s:.0f}/s)")
    if real:
        ours_by_name = dict(zip([name for name, _ in cases], best, strict=False))
        print(f"\n{'same client, calls/s':<{width}}  {'orchestra':>9}  {'rosmaster':>9}  "
              f"{'ratio':>6}")
        for (name, _), value in zip(theirs, best_real, strict=False):
            mine = ours_by_name[name]
            print(f"{name:<{width}}  {mine:9.0f}  {value:9.0f}  {mine / value:5.1f}x")
        print(f"{'upload_params, 1,000 params (ms)':<{width}}  {upload_s * 1e3:9.1f}  "
              f"{r_upload_s * 1e3:9.1f}  {r_upload_s / upload_s:5.1f}x")
        print(f"{f'{n:,} registrations, sequential (ms)':<{width}}  {register_s * 1e3:9.0f}  "
              f"{r_register_s * 1e3:9.0f}  {r_register_s / register_s:5.1f}x")
        print("ratio = orchestra throughput / rosmaster throughput (higher: orchestra faster)")
    print(ros1.load_average())


if __name__ == "__main__":
    main()
