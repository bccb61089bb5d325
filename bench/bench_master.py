"""Master throughput: parameter calls per second and getSystemState at 1,000 registrations.

Plain Python, no pytest. Every figure is measured in this run next to a baseline measured the
same way in the same run, so ratios stay meaningful on a busy machine:

- baseline "stdlib no-op": a threaded stdlib SimpleXMLRPCServer speaking HTTP/1.0 (one TCP
  connection per call, like rosmaster's server) whose method returns [1, "", 0] at once;
  this is the cost of an XML-RPC round trip with no master logic at all.
- baseline "keep-alive no-op": the same no-op method on orchestra's server class, to separate
  the transport gain from the master's own cost.

Usage: ``python bench/bench_master.py [--seconds 1.0]``
"""
from __future__ import annotations

import argparse
import socketserver
import threading
import time
import xmlrpc.client
from xmlrpc.server import SimpleXMLRPCServer

from orchestra.master import start_master, upload_params
from orchestra.master.server import ThreadedXMLRPCServer


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


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=1.0, help="time per measurement")
    parser.add_argument("--rounds", type=int, default=3,
                        help="measure everything this many times, interleaved; keep the best "
                             "(the machine is shared: the best round is the least disturbed)")
    parser.add_argument("--registrations", type=int, default=1000)
    args = parser.parse_args()
    n = args.registrations

    stdlib = _StdlibThreaded(("127.0.0.1", 0), logRequests=False)
    stdlib.register_function(_noop, "noop")
    _serve(stdlib)
    keepalive = ThreadedXMLRPCServer(("127.0.0.1", 0))
    keepalive.register_function(_noop, "noop")
    _serve(keepalive)
    master = start_master(port=0)   # parameters and a leaf to read/write
    graph = start_master(port=0)    # 1,000 registrations
    try:
        p_std = xmlrpc.client.ServerProxy(f"http://127.0.0.1:{stdlib.server_address[1]}/")
        p_ka = xmlrpc.client.ServerProxy(f"http://127.0.0.1:{keepalive.server_address[1]}/")
        m = xmlrpc.client.ServerProxy(master.uri)
        g = xmlrpc.client.ServerProxy(graph.uri)
        m.setParam("/bench", "/robot/gain", 1.5)
        params = {f"/ns{i % 10}/node{i}/param": i for i in range(1000)}
        start = time.perf_counter()
        upload_params(master.uri, params, ["/ns0"])
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

        counter = iter(range(10 ** 9))
        # the master's own share of a big reply: dispatch plus XML encoding, without the
        # client's (pure-Python) XML parsing that dominates the round trip
        def server_side(api, method, *call_args):
            return lambda: xmlrpc.client.dumps((api._dispatch(method, call_args),),
                                               methodresponse=True)
        cases = [
            ("stdlib no-op (HTTP/1.0, rosmaster transport)", lambda: p_std.noop("/b", "/k")),
            ("orchestra server no-op (keep-alive)", lambda: p_ka.noop("/b", "/k")),
            ("getParam (leaf)", lambda: m.getParam("/bench", "/robot/gain")),
            ("setParam (leaf)", lambda: m.setParam("/bench", "/robot/gain", next(counter))),
            ("getParam('/') with 1,000 params", lambda: m.getParam("/b", "/")),
            ("  same, server side only (dispatch + encode)",
             server_side(master.api, "getParam", "/b", "/")),
            (f"getSystemState with {n:,} registrations", lambda: g.getSystemState("/b")),
            ("  same, server side only (dispatch + encode)",
             server_side(graph.api, "getSystemState", "/b")),
        ]
        best = [0.0] * len(cases)
        for _ in range(args.rounds):
            for i, (_, fn) in enumerate(cases):
                best[i] = max(best[i], rate(fn, args.seconds / args.rounds))
    finally:
        for server in (stdlib, keepalive):
            server.shutdown()
            server.server_close()
        master.shutdown()
        graph.shutdown()

    base = best[0]
    width = max(len(name) for name, _ in cases)
    print(f"{'measurement':<{width}}  {'calls/s':>9}  {'ms/call':>8}  {'x baseline':>10}")
    for (name, _), value in zip(cases, best):
        print(f"{name:<{width}}  {value:9.0f}  {1000 / value:8.3f}  {value / base:10.2f}")
    print(f"upload_params: 1,000 params + 1 clear in one multicall: {upload_s * 1000:.1f} ms")
    print(f"{n:,} registrations (pub/sub/service mix), sequential: {register_s * 1000:.0f} ms "
          f"({n / register_s:.0f}/s)")


if __name__ == "__main__":
    main()
