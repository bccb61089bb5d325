"""Master throughput: orchestra's master against the real rosmaster, both as processes.

Plain Python, no pytest. Both masters run as separate processes started the same way and
pinned to the same CPU (``orchestra core -p PORT --no-rosout`` and ``rosmaster --core -p
PORT``), and are filled and called by the same client code in this process: per-call rates
of getParam/setParam, getParam('/') with 1,000 params, getSystemState with 1,000
registrations, and the time of 1,000 sequential registerPublisher calls and of one multicall
of 1,000 setParam.

Two clients, each used identically for both masters, each row labelled with its client:
``xmlrpc.client`` (what rospy uses; it costs ~70 us a call itself, which hides differences
between servers) and ``raw``: requests written by ``xmlrpc.client.dumps`` before the clock
starts, sent on one kept-alive HTTP/1.1 connection, the reply read up to its
Content-Length and only its status code checked: about as little as a client can do, so
these rows show what the servers themselves cost.

Where the client runs matters more than either server on this kind of machine: a call is a
round trip, and with the client on another CPU than the master each call pays two cross-CPU
wake-ups (on this 2-vCPU VM ~100 us together, more than rosmaster's own work), with both on
one CPU two context switches (a few us). Left to the scheduler, the client landed on one or
the other from run to run, and the ratios with it (getParam 1.4x-2.8x). So this process
(every client) is pinned too: by default to the masters' CPU (``--client-cpu``), where a
call costs the client's work + the server's work + two switches; the ``[raw, client on
CPU n]`` rows repeat getParam/setParam with the client on another CPU, and the last line
gives the round-trip floor of each placement: the same raw client against a do-nothing
server (one recv, one sendall of a canned answer) pinned like the masters.

Every measurement is taken ``--rounds``
times, interleaved between the two masters; the tables show medians of the wall-clock
figures and of the master processes' own CPU time for the same calls (psutil; far less
sensitive than wall clock to other load on a shared machine). Skipped with a message when
/usr/bin/rosmaster is missing (orchestra's figures still print).

Usage: ``python bench/bench_master.py [--quick] [--seconds 1.0] [--rounds 5] [--cpu N]
[--client-cpu N]``
"""
from __future__ import annotations

import argparse
import functools
import itertools
import os
import shutil
import socket
import statistics
import subprocess
import sys
import time
import xmlrpc.client
from collections.abc import Callable
from urllib.parse import urlsplit

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import psutil  # noqa: E402
import ros1  # noqa: E402

PIN: list[str] = []
TIMED_REPEATS = 3  # runs of each timed case per round (its CPU time: their mean)


def rate(fn, seconds: float) -> tuple[float, int]:
    """(calls per second, calls made) of ``fn`` over about ``seconds`` (after a warm-up)."""
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
            return calls / (now - start), calls


class RawClient:
    """An HTTP/1.1 XML-RPC client that sends request bodies it is given, pre-built, on one
    kept-alive connection (re-opened when the server closes it) and checks only that the
    answer is HTTP 200 carrying ROS status code 1: the same few syscalls and byte scans for
    every server, so the server's own cost is what differs."""

    def __init__(self, uri: str) -> None:
        where = urlsplit(uri)
        self.address = (where.hostname or "127.0.0.1", where.port or 80)
        self.head = (f"POST / HTTP/1.1\r\nHost: {self.address[0]}:{self.address[1]}\r\n"
                     "User-Agent: bench\r\nContent-Type: text/xml\r\nContent-Length: ")
        self.sock: socket.socket | None = None
        self.buffer = b""

    def call(self, body: bytes) -> bytes:
        if self.sock is None:
            self.sock = socket.create_connection(self.address)
            self.sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
            self.buffer = b""
        self.sock.sendall(f"{self.head}{len(body)}\r\n\r\n".encode() + body)
        buffer = self.buffer
        while (end := buffer.find(b"\r\n\r\n")) < 0:
            buffer += self._recv()
        head = buffer[:end].lower()
        start = head.index(b"content-length:") + 15
        stop = head.find(b"\r\n", start)
        length = int(head[start:stop if stop >= 0 else None])
        end += 4
        while len(buffer) < end + length:
            buffer += self._recv()
        reply, self.buffer = buffer[end:end + length], buffer[end + length:]
        if not head.startswith(b"http/1.1 200") or b"connection: close" in head:
            self.close()
        if not head.startswith((b"http/1.0 200", b"http/1.1 200")) or (
                b"<value><int>1</int></value>" not in reply[:200]):
            raise RuntimeError(f"unexpected answer {head!r} {reply[:300]!r}")
        return reply

    def _recv(self) -> bytes:
        assert self.sock is not None
        chunk = self.sock.recv(1 << 16)
        if not chunk:
            raise ConnectionError("the server closed the connection")
        return chunk

    def close(self) -> None:
        if self.sock is not None:
            self.sock.close()
            self.sock = None


def request(method: str, *params: object) -> bytes:
    return xmlrpc.client.dumps(params, method).encode()


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

    def cpu_seconds(self) -> float:
        """CPU time (user + system) the master process has used so far."""
        times = psutil.Process(self.proc.pid).cpu_times()
        return times.user + times.system

    def stop(self) -> None:
        ros1.kill_tree(self.proc.pid)
        self.proc.wait(10)


_CANNED = xmlrpc.client.dumps(((1, "Parameter [/robot/gain]", 1.5),),
                              methodresponse=True).encode()


def floor_server(port: int) -> None:
    """The round-trip floor: a do-nothing HTTP server, one thread, one connection at a time,
    answering every request with a canned ROS answer (one recv, one sendall a request, as
    little as a Python server can do). Run as ``bench_master.py --floor-server -p PORT``."""
    answer = (b"HTTP/1.1 200 OK\r\nContent-Type: text/xml\r\nContent-Length: %d\r\n\r\n"
              % len(_CANNED)) + _CANNED
    with socket.create_server(("127.0.0.1", port)) as listener:
        while True:
            conn, _ = listener.accept()
            conn.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
            buffer = b""
            with conn:
                while chunk := conn.recv(1 << 16):
                    buffer += chunk
                    while (end := buffer.find(b"\r\n\r\n")) >= 0:
                        start = buffer.lower().find(b"content-length:", 0, end) + 15
                        size = int(buffer[start:buffer.find(b"\r\n", start)])
                        if len(buffer) < end + 4 + size:
                            break
                        buffer = buffer[end + 4 + size:]
                        conn.sendall(answer)


def floor_process() -> MasterProcess:
    return MasterProcess([sys.executable, os.path.abspath(__file__), "--floor-server"],
                         dict(os.environ))


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


def _publisher(i: int, prefix: str) -> tuple[str, str, str, str]:
    return (f"/pub{i}", f"{prefix}/topic{i}", "std_msgs/String",
            f"http://127.0.0.1:{40000 + i % 20000}/")


def register_publishers(uri: str, n: int, prefix: str) -> float:
    """Seconds for ``n`` sequential registerPublisher calls (new topics every round)."""
    g = xmlrpc.client.ServerProxy(uri)
    start = time.perf_counter()
    for i in range(n):
        g.registerPublisher(*_publisher(i, prefix))
    return time.perf_counter() - start


def register_publishers_raw(uri: str, n: int, prefix: str) -> float:
    """``register_publishers`` through the raw client (requests built before the clock)."""
    bodies = [request("registerPublisher", *_publisher(i, prefix)) for i in range(n)]
    client = RawClient(uri)
    client.call(request("getPid", "/bench"))  # connected before the clock starts
    start = time.perf_counter()
    for body in bodies:
        client.call(body)
    took = time.perf_counter() - start
    client.close()
    return took


def multicall_set(uri: str, n: int, prefix: str) -> float:
    """Seconds for one system.multicall of ``n`` setParam calls."""
    multi = xmlrpc.client.MultiCall(xmlrpc.client.ServerProxy(uri))
    for i in range(n):
        multi.setParam("/bench", f"{prefix}/p{i}", i)
    start = time.perf_counter()
    results = list(multi())
    took = time.perf_counter() - start
    assert len(results) == n
    return took


def multicall_set_raw(uri: str, n: int, prefix: str) -> float:
    """``multicall_set`` through the raw client (the request built before the clock)."""
    body = request("system.multicall", [
        {"methodName": "setParam", "params": ["/bench", f"{prefix}/p{i}", i]}
        for i in range(n)])
    client = RawClient(uri)
    client.call(request("getPid", "/bench"))
    start = time.perf_counter()
    reply = client.call(body)
    took = time.perf_counter() - start
    client.close()
    assert reply.count(b"<int>1</int>") == n
    return took


def undo(uri: str, run: Callable[[str, int, str], float], n: int, prefix: str) -> None:
    """Take back what a timed case added (untimed), so that the rows measured on the same
    masters keep their 1,000 params and 1,000 registrations round after round."""
    client = RawClient(uri)
    if "register" in run.__name__:
        for i in range(n):
            node, topic, _, api = _publisher(i, prefix)
            client.call(request("unregisterPublisher", node, topic, api))
    else:
        client.call(request("deleteParam", "/bench", prefix))
    client.close()


def rate_cases(param_uri: str, graph_uri: str, n: int, other_cpu: int | None
               ) -> list[tuple[str, Callable[[], object], int | None]]:
    """The calls measured on any master, through each client: (row, call, the CPU the client
    moves to for that row; None: where this process is pinned)."""
    m = xmlrpc.client.ServerProxy(param_uri)
    g = xmlrpc.client.ServerProxy(graph_uri)
    counter = iter(range(10 ** 9))
    raw_m, raw_g = RawClient(param_uri), RawClient(graph_uri)
    get = request("getParam", "/bench", "/robot/gain")
    sets = itertools.cycle([request("setParam", "/bench", "/robot/gain", i)
                            for i in range(1000)])  # a new value every call, as above
    get_all = request("getParam", "/b", "/")
    state = request("getSystemState", "/b")
    cases: list[tuple[str, Callable[[], object], int | None]] = [
        ("[xmlrpc.client] getParam (leaf), calls/s", lambda: m.getParam("/bench", "/robot/gain"),
         None),
        ("[xmlrpc.client] setParam (leaf), calls/s",
         lambda: m.setParam("/bench", "/robot/gain", next(counter)), None),
        ("[xmlrpc.client] getParam('/') with 1,000 params, calls/s",
         lambda: m.getParam("/b", "/"), None),
        (f"[xmlrpc.client] getSystemState with {n:,} registrations, calls/s",
         lambda: g.getSystemState("/b"), None),
        ("[raw] getParam (leaf), calls/s", lambda: raw_m.call(get), None),
        ("[raw] setParam (leaf), calls/s", lambda: raw_m.call(next(sets)), None),
        ("[raw] getParam('/') with 1,000 params, calls/s", lambda: raw_m.call(get_all), None),
        (f"[raw] getSystemState with {n:,} registrations, calls/s",
         lambda: raw_g.call(state), None),
    ]
    if other_cpu is not None:
        cases += [
            (f"[raw, client on CPU {other_cpu}] getParam (leaf), calls/s",
             lambda: raw_m.call(get), other_cpu),
            (f"[raw, client on CPU {other_cpu}] setParam (leaf), calls/s",
             lambda: raw_m.call(next(sets)), other_cpu),
        ]
    return cases


def measure_rate(fn: Callable[[], object], seconds: float, cpu: int | None
                 ) -> tuple[float, int]:
    """``rate(fn, seconds)`` with this process moved to ``cpu`` meanwhile (None: as is)."""
    if cpu is None:
        return rate(fn, seconds)
    pinned = os.sched_getaffinity(0)
    os.sched_setaffinity(0, {cpu})
    try:
        return rate(fn, seconds)
    finally:
        os.sched_setaffinity(0, pinned)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=None,
                        help="time per rate measurement (default 1.0; 0.3 with --quick)")
    parser.add_argument("--rounds", type=int, default=5,
                        help="measure everything this many times, interleaved; medians")
    parser.add_argument("--registrations", type=int, default=1000)
    parser.add_argument("--cpu", type=int, default=None,
                        help="pin both masters to this CPU (default: the last; -1: no pinning)")
    parser.add_argument("--client-cpu", type=int, default=None,
                        help="pin this process (the clients) to this CPU (default: the "
                             "masters'; -1: no pinning)")
    parser.add_argument("--quick", action="store_true", help="shorter measurements")
    parser.add_argument("--floor-server", action="store_true", help=argparse.SUPPRESS)
    parser.add_argument("-p", type=int, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.floor_server:
        floor_server(args.p)
        return
    seconds = args.seconds or (0.3 if args.quick else 1.0)
    n = args.registrations
    cpus = sorted(os.sched_getaffinity(0))
    cpu = cpus[-1] if args.cpu is None else args.cpu
    if cpu >= 0 and shutil.which("taskset"):
        PIN[:] = ["taskset", "-c", str(cpu)]
    client_cpu = cpu if args.client_cpu is None else args.client_cpu
    other_cpu = next((c for c in cpus if c != client_cpu), None) if client_cpu >= 0 else None
    if client_cpu >= 0:
        os.sched_setaffinity(0, {client_cpu})
    print(ros1.load_average())
    print(f"masters (and the floor server) on CPU {cpu if PIN else 'any'}; clients on CPU "
          f"{client_cpu if client_cpu >= 0 else 'any'}"
          + (f", and on CPU {other_cpu} in the [raw, client on CPU {other_cpu}] rows"
             if other_cpu is not None else ""))
    sides: dict[str, list[MasterProcess]] = {}
    floor: MasterProcess | None = None
    floors: dict[int | None, list[float]] = {None: [], other_cpu: []}
    get_body = request("getParam", "/bench", "/robot/gain")
    try:
        floor = floor_process()
        sides["orchestra"] = [orchestra_master(), orchestra_master()]
        if ros1.tool("rosmaster") is None:
            ros1.skip("the real rosmaster", "rosmaster (ROS 1)")
        else:
            sides["rosmaster"] = [real_rosmaster(), real_rosmaster()]
        for params, graph in sides.values():
            populate(params.uri, graph.uri, n)
        names = [name for name, _, _ in rate_cases("http://x/", "http://x/", n, other_cpu)]
        timed = [("[xmlrpc.client] 1,000 registerPublisher, sequential, ms", register_publishers),
                 ("[xmlrpc.client] multicall of 1,000 setParam, ms", multicall_set),
                 ("[raw] 1,000 registerPublisher, sequential, ms", register_publishers_raw),
                 ("[raw] multicall of 1,000 setParam, ms", multicall_set_raw)]
        names += [name for name, _ in timed]
        results: dict[str, list[list[float]]] = {side: [[] for _ in names] for side in sides}
        # the masters' own CPU time: per call (rate rows, us) or per run (timed rows, ms)
        cpu: dict[str, list[list[float]]] = {side: [[] for _ in names] for side in sides}
        for round_no in range(args.rounds):
            floor_client = RawClient(floor.uri)
            for where in floors:
                floors[where].append(
                    measure_rate(functools.partial(floor_client.call, get_body), seconds,
                                 where)[0])
            floor_client.close()
            for side, masters in sides.items():   # interleaved
                params, graph = masters
                cases = rate_cases(params.uri, graph.uri, n, other_cpu)
                for i, (_, fn, where) in enumerate(cases):
                    before = sum(m.cpu_seconds() for m in masters)
                    calls_per_s, calls = measure_rate(fn, seconds, where)
                    used = sum(m.cpu_seconds() for m in masters) - before
                    results[side][i].append(calls_per_s)
                    cpu[side][i].append(used / calls * 1e6)
                for j, (_, run) in enumerate(timed):
                    uri = graph.uri if "register" in run.__name__ else params.uri
                    before = sum(m.cpu_seconds() for m in masters)
                    for repeat in range(TIMED_REPEATS):   # CPU time is counted in 10 ms ticks
                        results[side][len(cases) + j].append(
                            run(uri, 1000, f"/r{round_no}/{j}/{repeat}") * 1e3)
                    used = sum(m.cpu_seconds() for m in masters) - before
                    cpu[side][len(cases) + j].append(used * 1e3 / TIMED_REPEATS)
                    for repeat in range(TIMED_REPEATS):
                        undo(uri, run, 1000, f"/r{round_no}/{j}/{repeat}")
    finally:
        for master in [*(m for masters in sides.values() for m in masters), floor]:
            if master is not None:
                master.stop()

    _table(f"wall clock, median of {args.rounds} rounds", names, results)
    print("ratio = orchestra / rosmaster (calls/s rows: higher is faster; ms rows: lower is "
          "faster)")
    cpu_names = [name.replace("calls/s", "master CPU us per call").replace(
        ", ms", ", master CPU ms") for name in names]
    _table(f"the master process's CPU time, median of {args.rounds} rounds", cpu_names, cpu)
    print("ratio = orchestra / rosmaster (lower is cheaper; a master's calls/s on a CPU of "
          "its own is 1e6 / us per call)")
    for where, rates in floors.items():
        floor_rate = statistics.median(rates)
        print(f"round-trip floor, client on CPU {client_cpu if where is None else where}: a "
              f"do-nothing server answers {floor_rate:.0f} calls/s ({1e6 / floor_rate:.1f} us "
              "a call), median")
    print(ros1.load_average())


def _table(title: str, names: list[str], results: dict[str, list[list[float]]]) -> None:
    width = max(len(name) for name in names)
    med = {side: [statistics.median(v) for v in values] for side, values in results.items()}
    print(f"\n{title:<{width}}  {'orchestra':>10}  {'rosmaster':>10}  {'ratio':>6}")
    for i, name in enumerate(names):
        ours = med["orchestra"][i]
        if "rosmaster" in med:
            theirs = med["rosmaster"][i]
            print(f"{name:<{width}}  {ours:10.1f}  {theirs:10.1f}  {ours / theirs:5.2f}x")
        else:
            print(f"{name:<{width}}  {ours:10.1f}")


if __name__ == "__main__":
    main()
