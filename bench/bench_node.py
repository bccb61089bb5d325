#!/usr/bin/env python3
"""Node runtime speed: one-way latency and throughput of topics, service calls per second.

Every figure is measured here, in one run, next to a baseline measured the same way on the
same machine: plain Python processes exchanging the same bytes over a loopback TCP socket
with no ROS layer at all. Ratios (orchestra / baseline) are what to compare between
machines; absolute numbers depend on the CPU and on what else runs.

    python bench/bench_node.py            # full run (~5 minutes)
    python bench/bench_node.py --quick    # fewer topic samples (~5 minutes)
    python bench/bench_node.py --rows service    # only the rospy service rows (issue 15)
    python bench/bench_node.py --rows twist100   # only the rospy 100 Hz latency rows
    python bench/bench_node.py --rows twist100 --contend 1   # ... with the subscribers'
                                                 # CPU kept busy by another process
    python bench/bench_node.py --orchestra-python /usr/bin/python3   # orchestra on the
                                                 # ROS 1 interpreter build (see below)

Processes: an in-process master, then a publisher process and a subscriber process (or a
service and a client process). One-way latency = receive time - send time, both read from
CLOCK_MONOTONIC, which every process on the machine shares.

Against the real ROS 1 rospy (Debian's, run by /usr/bin/python3): the same roles, same
messages and timing, as rospy->rospy, and mixed (orchestra->rospy, rospy->orchestra); service
calls/s rospy client->rospy service next to orchestra's. All pairs look each other up through
the same (orchestra) master, which is not on the measured path of topics (it is on a plain
service call's: each call looks the service up, as rospy's does). Skipped with a message when
rospy is missing.

Interpreters: rospy runs on the ROS 1 interpreter (Debian's, built with PGO and LTO),
orchestra on the one running this script; an interpreter built without those (pyenv's
default) runs the same bytecode 1.2-1.4x slower, which is then in every ratio here.
``--orchestra-python /usr/bin/python3`` runs orchestra's roles on the ROS 1 interpreter
(with this one's site-packages on its path) to compare the implementations alone.

Pinning (``--pin split``, the default on a machine with 2+ CPUs): every publisher and client
runs on CPU 0, every subscriber and service on CPU 1, and this process (the master) on CPU
1 too, whichever implementation plays the role. Unpinned, a request/reply rate doubles or
halves with where the scheduler happens to put the two processes (same CPU: a direct switch;
two CPUs: a cross-CPU wake-up per message), which made persistent service calls bimodal
(0.4-3.2x from one run to the next). ``--pin none`` leaves placement to the scheduler.

Service rows run every pair in each of ``--rounds`` rounds, the pairs' order rotated each
round; they print each round (with the load average when it began), the medians, and each
round's ratio against rospy->rospy as ``median [min-max]``: one round that another process
spoiled shows as such instead of deciding the figure. The 100 Hz rows compare two pairs AT
ONCE instead (orchestra's subscriber next to rospy's, fed by one rospy publisher; orchestra's
publisher next to rospy's, read by one rospy subscriber), their messages 5 ms apart on
absolute times, so both see the same machine; the tail of a 100 Hz stream is mostly how
long the receiving thread waits for its CPU, which two runs seconds apart do not share.
Next to the p99 they print the share of messages later than 1 ms: when ~1 % of the
messages wait for a CPU (ms) and the rest do not (~0.1-0.3 ms), the p99 of 1,000 jumps
between the two with a message or two more or less; the share moves smoothly.
Every child runs in its own session (its own autogroup), as launched nodes do. A round makes
``--calls`` plain and ``--persistent-calls`` persistent calls per pair (a kept connection's
call is ~10x faster, so 10x as many make a round of similar length), and the client's CPU
per call is printed next to the rates.
"""
from __future__ import annotations

import argparse
import contextlib
import json
import os
import random
import shutil
import socket
import statistics
import struct
import subprocess
import sys
import time

HERE = os.path.abspath(__file__)
IMAGE_BYTES = 640 * 480 * 3
IMPL = "orchestra"  # the node API a child role uses: "orchestra" or "rospy" (--impl)


def node_api():
    """The rospy-like module of this child: orchestra.node or the real rospy."""
    if IMPL == "rospy":
        import rospy
        return rospy
    import orchestra.node as api
    return api


def message_class(type_name: str):
    if IMPL == "rospy":
        import importlib
        pkg, name = type_name.split("/")
        return getattr(importlib.import_module(f"{pkg}.msg"), name)
    from orchestra.node.msg import get_message_class
    return get_message_class(type_name)


def service_classes(type_name: str):
    """(service class, response class) in this child's node API."""
    if IMPL == "rospy":
        import importlib
        pkg, name = type_name.split("/")
        module = importlib.import_module(f"{pkg}.srv")
        return getattr(module, name), getattr(module, name + "Response")
    from orchestra.node.msg import get_service_class
    cls = get_service_class(type_name)
    return cls, cls.Response


def serialized_size(msg) -> int:
    if hasattr(msg, "serialize_bytes"):
        return len(msg.serialize_bytes())
    import io
    buf = io.BytesIO()
    msg.serialize(buf)
    return len(buf.getvalue())


def now() -> float:
    return time.monotonic()


#: a message later than this waited for its CPU (a time slice of another task or a
#: scheduler tick, 4 ms at HZ=250), not for our code (~0.1-0.3 ms)
LATE = 0.001


def summarize(latencies: list[float]) -> dict:
    ordered = sorted(latencies)
    p99 = ordered[min(len(ordered) - 1, int(len(ordered) * 0.99))]
    return {"median_us": statistics.median(ordered) * 1e6, "p99_us": p99 * 1e6,
            "n": len(ordered), "late_pct": 100 * sum(x > LATE for x in ordered) / len(ordered)}


def emit(obj: dict) -> None:
    sys.stdout.write(json.dumps(obj) + "\n")
    sys.stdout.flush()


# --- roles run in child processes ----------------------------------------------------------------

def make_message(kind: str):
    if kind == "twist":
        return message_class("geometry_msgs/Twist")()
    img = message_class("sensor_msgs/Image")(height=480, width=640, encoding="rgb8",
                                             step=640 * 3, data=bytes(IMAGE_BYTES))
    return img


def stamp(kind: str, msg, t: float) -> None:
    if kind == "twist":
        msg.linear.x = t
    else:
        msg.header.stamp.secs, msg.header.stamp.nsecs = int(t), int((t % 1) * 1e9)


def read_stamp(kind: str, msg) -> float:
    if kind == "twist":
        return msg.linear.x
    return msg.header.stamp.secs + msg.header.stamp.nsecs / 1e9


def role_sub(kind: str, count: int, burst: int) -> None:
    import threading

    rospy = node_api()
    msg = make_message(kind)
    latencies: list[float] = []
    burst_times: list[float] = []
    done = threading.Event()

    def callback(m):
        t = now()
        if m.angular.z if kind == "twist" else m.header.frame_id == "burst":
            if not burst_times:
                burst_times.append(read_stamp(kind, m))  # when the burst was started
            burst_times.append(t)
            if len(burst_times) > burst:
                done.set()
        else:
            latencies.append(t - read_stamp(kind, m))

    rospy.init_node(f"bench_sub_{kind}", disable_signals=True)
    rospy.Subscriber("/bench", type(msg), callback, queue_size=burst or 10)
    emit({"ready": True})
    line = sys.stdin.readline()  # "latency done" from the parent
    # every sample too when there is no burst (the 100 Hz runs: their rounds are pooled)
    emit({"latency": summarize(latencies), **({} if burst else {"samples": latencies})})
    if not burst:
        rospy.signal_shutdown("done")
        return
    done.wait(float(line.split()[-1]) if line.strip() else 30.0)
    received = len(burst_times) - 1
    span = burst_times[-1] - burst_times[0] if received > 0 else float("nan")
    emit({"throughput": {"received": received, "msgs_per_s": received / span,
                         "mb_per_s": received * serialized_size(msg) / span / 1e6}})
    rospy.signal_shutdown("done")


def role_pub(kind: str, count: int, burst: int, gap: float) -> None:
    rospy = node_api()
    msg = make_message(kind)
    rospy.init_node(f"bench_pub_{kind}", disable_signals=True)
    pub = rospy.Publisher("/bench", type(msg), queue_size=burst or 10)
    while pub.get_num_connections() < 1:
        time.sleep(0.01)
    time.sleep(0.2)
    for _ in range(count):
        stamp(kind, msg, now())
        pub.publish(msg)
        time.sleep(gap)
    time.sleep(0.3)
    emit({"latency_sent": count})
    sys.stdin.readline()  # go for the burst
    if not burst:
        rospy.signal_shutdown("done")
        return
    if kind == "twist":
        msg.angular.z = 1.0
    else:
        msg.header.frame_id = "burst"
    stamp(kind, msg, now())
    pub.publish(msg)  # the first burst message carries the start time
    for _ in range(burst - 1):
        pub.publish(msg)
    impl = getattr(pub, "_impl", None)
    deadline = now() + 30
    if IMPL == "orchestra":
        while now() < deadline and not all(c.idle() for c in impl.connections):
            time.sleep(0.01)
    # rospy's publish() hands each message to the connection's writer thread; the parent
    # waits for the subscriber's count either way
    emit({"burst_sent": burst})
    sys.stdin.readline()
    rospy.signal_shutdown("done")


def role_multi_sub(topics: list[str]) -> None:
    """One subscriber process on several Twist topics (the 100 Hz rows): every sample kept
    per topic, so two publishers' messages reach the same subscriber process."""
    rospy = node_api()
    cls = message_class("geometry_msgs/Twist")
    samples: dict[str, list[float]] = {t: [] for t in topics}

    def callback(m, topic):
        samples[topic].append(now() - m.linear.x)

    rospy.init_node(f"bench_sub_{os.getpid()}", disable_signals=True)
    for topic in topics:
        rospy.Subscriber(topic, cls, callback, callback_args=topic, queue_size=10)
    emit({"ready": True})
    sys.stdin.readline()  # "latency done" from the parent
    emit({"samples": samples})
    rospy.signal_shutdown("done")


#: each 100 Hz period starts up to this much late, at random (the same draw for both
#: streams): something on the machine that wakes exactly every 2.56 s (or any multiple of
#: 10 ms) otherwise always hits the same one of the two streams and decides its p99
JITTER = 0.002


def role_phase_pub(topics: list[str], phases: list[float], count: int, period: float,
                   subscribers: int) -> None:
    """Publish a Twist on each topic every ``period`` s at its own phase, on absolute times
    from a start time the parent gives (CLOCK_MONOTONIC, shared by every process): two
    publisher processes, or two topics of one, then send in turn ``period/2`` apart."""
    rospy = node_api()
    cls = message_class("geometry_msgs/Twist")
    rospy.init_node(f"bench_pub_{os.getpid()}", disable_signals=True)
    pubs = [rospy.Publisher(t, cls, queue_size=10) for t in topics]
    msg = cls()
    while any(p.get_num_connections() < subscribers for p in pubs):
        time.sleep(0.01)
    emit({"connected": True})
    t0, seed = sys.stdin.readline().split()
    jitter = random.Random(int(seed))  # the same draws in every publisher of the run
    order = sorted(zip(phases, pubs, strict=True), key=lambda x: x[0])
    for k in range(count):
        start = float(t0) + k * period + jitter.uniform(0, JITTER)
        for phase, pub in order:
            delay = start + phase - now()
            if delay > 0:
                time.sleep(delay)
            msg.linear.x = now()
            pub.publish(msg)
    time.sleep(0.3)
    emit({"latency_sent": count})
    sys.stdin.readline()
    rospy.signal_shutdown("done")


def role_service() -> None:
    rospy = node_api()
    SetBool, Response = service_classes("std_srvs/SetBool")
    rospy.init_node("bench_service", disable_signals=True)
    rospy.Service("/bench_srv", SetBool, lambda req: Response(success=req.data))
    emit({"ready": True})
    sys.stdin.readline()
    rospy.signal_shutdown("done")


def role_client(calls: int, persistent_calls: int) -> None:
    rospy = node_api()
    SetBool, _ = service_classes("std_srvs/SetBool")
    rospy.init_node("bench_client", disable_signals=True)
    rospy.wait_for_service("/bench_srv", timeout=10)
    out, cpu = {}, {}
    for persistent, n in ((False, calls), (True, persistent_calls)):
        key = "persistent" if persistent else "plain"
        proxy = rospy.ServiceProxy("/bench_srv", SetBool, persistent=persistent)
        proxy(data=True)
        start, start_cpu = now(), time.process_time()
        for _ in range(n):
            assert proxy(data=True).success
        out[key] = n / (now() - start)
        cpu[key] = (time.process_time() - start_cpu) / n * 1e6  # the client's, all threads
        if persistent:
            proxy.close()
    emit({"calls_per_s": out, "client_cpu_us": cpu})
    rospy.signal_shutdown("done")


# --- baseline: the same bytes over a bare socket -------------------------------------------------

def role_raw_server(size: int, count: int, burst: int) -> None:
    srv = socket.socket()
    srv.bind(("127.0.0.1", 0))
    srv.listen(1)
    emit({"port": srv.getsockname()[1]})
    conn, _ = srv.accept()
    conn.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
    f = conn.makefile("rb")
    lat: list[float] = []
    for _ in range(count):
        (n,) = struct.unpack("<I", f.read(4))
        body = f.read(n)
        lat.append(now() - struct.unpack_from("<d", body)[0])
    start = None
    for _ in range(burst):
        (n,) = struct.unpack("<I", f.read(4))
        body = f.read(n)
        if start is None:
            start = struct.unpack_from("<d", body)[0]
    span = now() - start
    emit({"latency": summarize(lat), "throughput": {"msgs_per_s": burst / span,
                                                    "mb_per_s": burst * size / span / 1e6}})
    # request/response round trips for the service baseline
    while True:
        head = f.read(4)
        if len(head) < 4:
            break
        (n,) = struct.unpack("<I", head)
        f.read(n)
        conn.sendall(b"\x01" + struct.pack("<I", 1) + b"\x01")


def raw_baseline(size: int, count: int, burst: int, calls: int, gap: float) -> dict:
    """The same bytes over a bare socket; this process is the sending side, on the
    publisher's CPU while it runs."""
    master_cpus = os.sched_getaffinity(0)
    if CPUS:
        os.sched_setaffinity(0, {CPUS["raw_client"]})
    try:
        return _raw_baseline(size, count, burst, calls, gap)
    finally:
        os.sched_setaffinity(0, master_cpus)


def _raw_baseline(size: int, count: int, burst: int, calls: int, gap: float) -> dict:
    proc = child(dict(os.environ), "raw_server", "--size", str(size), "--count", str(count),
                 "--burst", str(burst))
    port = json.loads(proc.stdout.readline())["port"]
    sock = socket.create_connection(("127.0.0.1", port))
    sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
    payload = bytearray(size)
    for _ in range(count):
        struct.pack_into("<d", payload, 0, now())
        sock.sendall(struct.pack("<I", size) + payload)
        time.sleep(gap)
    struct.pack_into("<d", payload, 0, now())
    for _ in range(burst):
        sock.sendall(struct.pack("<I", size) + payload)
    result = json.loads(proc.stdout.readline())
    f = sock.makefile("rb")
    start = now()
    for _ in range(calls):
        sock.sendall(struct.pack("<I", 1) + b"\x01")
        f.read(6)
    result["calls_per_s"] = calls / (now() - start)
    f.close()
    sock.close()
    proc.wait(10)
    return result


# --- driver ---------------------------------------------------------------------------------------

#: the CPU of each role under ``--pin split`` (None: unpinned); "master" is this process
CPUS: dict[str, int] | None = None
SPLIT = {"pub": 0, "client": 0, "raw_client": 0, "phase_pub": 0, "sub": 1, "multi_sub": 1,
         "service": 1, "raw_server": 1,
         "master": 1}


#: the interpreter of orchestra's roles (--orchestra-python; None: this one)
ORCHESTRA_PYTHON: str | None = None


def orchestra_path() -> list[str]:
    """What another interpreter of the same Python version needs on its path to run
    orchestra as this one does: orchestra's source tree and this interpreter's
    site-packages (its dependencies; the same minor version shares their binary ABI)."""
    import sysconfig
    root = os.path.dirname(os.path.dirname(HERE))
    paths = sysconfig.get_paths()
    return [root, *dict.fromkeys((paths["purelib"], paths["platlib"]))]


def child(env: dict, role: str, *args: str, impl: str = "orchestra") -> subprocess.Popen:
    """A role in a child process: orchestra's interpreter, or the ROS 1 one for rospy."""
    if impl == "rospy":
        import ros1
        python = ros1.ROS1_PYTHON
        env = ros1.base_env(ROS_MASTER_URI=env["ROS_MASTER_URI"], PYTHONUNBUFFERED="1")
    elif ORCHESTRA_PYTHON:
        python = ORCHESTRA_PYTHON
        env = dict(env, PYTHONPATH=os.pathsep.join(orchestra_path()))
    else:
        python = sys.executable
    pin = ["--cpu", str(CPUS[role])] if CPUS else []
    # each in its own session, as roslaunch and orchestra start nodes: its own autogroup,
    # so it competes for its CPU as a launched node does
    return subprocess.Popen([python, HERE, "--impl", impl, "--role", role, *pin, *args], env=env,
                            stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True,
                            start_new_session=True)


def read(proc: subprocess.Popen, key: str) -> dict:
    while True:
        line = proc.stdout.readline()
        if not line:
            raise RuntimeError(f"child ended before reporting {key}")
        data = json.loads(line)
        if key in data:
            return data


def tell(proc: subprocess.Popen, text: str = "") -> None:
    proc.stdin.write(text + "\n")
    proc.stdin.flush()


def bench_topic(env: dict, kind: str, count: int, burst: int, gap: float,
                pub_impl: str = "orchestra", sub_impl: str = "orchestra") -> dict:
    """One publisher and one subscriber process: ``count`` messages ``gap`` s apart for
    latency, then (``burst`` > 0) a burst for throughput."""
    sub = child(env, "sub", "--kind", kind, "--count", str(count), "--burst", str(burst),
                impl=sub_impl)
    read(sub, "ready")
    pub = child(env, "pub", "--kind", kind, "--count", str(count), "--burst", str(burst),
                "--gap", str(gap), impl=pub_impl)
    read(pub, "latency_sent")
    tell(sub, "latency done 20")
    got = read(sub, "latency")
    latency = got["latency"]
    tell(pub)
    if not burst:
        for proc in (pub, sub):
            proc.wait(15)
        return {"latency": latency, "samples": got["samples"]}
    read(pub, "burst_sent")
    throughput = read(sub, "throughput")["throughput"]
    tell(pub)
    for proc in (pub, sub):
        proc.wait(15)
    return {"latency": latency, "throughput": throughput}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--role", default=None)
    parser.add_argument("--kind", default="twist")
    parser.add_argument("--count", type=int, default=2000)
    parser.add_argument("--burst", type=int, default=5000)
    parser.add_argument("--size", type=int, default=48)
    parser.add_argument("--calls", type=int, default=2000,
                        help="plain service calls per round (a connection each)")
    parser.add_argument("--persistent-calls", type=int, default=20000,
                        help="persistent service calls per round (~10x as many: a kept "
                             "connection's call is ~10x faster, and a round must last long "
                             "enough that one scheduler hiccup does not decide it)")
    parser.add_argument("--rows", default="all", choices=("all", "service", "twist100"),
                        help="all rows, or only the rospy service rows or the 100 Hz rows "
                             "(issue 15's node rows; each with its rounds and spread)")
    parser.add_argument("--rounds", type=int, default=5,
                        help="interleaved rounds of the service and 100 Hz rows")
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--impl", default="orchestra", choices=("orchestra", "rospy"),
                        help="(child roles) the node API to use")
    parser.add_argument("--json", action="store_true", help="Print one JSON document.")
    parser.add_argument("--gap", type=float, default=0.002,
                        help="(pub role) seconds between latency messages")
    parser.add_argument("--pin", default="split", choices=("split", "none"),
                        help="split: publishers/clients on CPU 0, subscribers/services and "
                             "the master on CPU 1; none: the scheduler decides")
    parser.add_argument("--topics", default="", help="(multi_sub, phase_pub) comma-separated")
    parser.add_argument("--phases", default="", help="(phase_pub) seconds, one per topic")
    parser.add_argument("--subscribers", type=int, default=1,
                        help="(phase_pub) connections to wait for on each topic")
    parser.add_argument("--twist100-count", type=int, default=1000,
                        help="100 Hz messages per compared pair and round")
    parser.add_argument("--contend", type=int, default=0,
                        help="CPU-bound processes kept busy on the subscribers' CPU during "
                             "the 100 Hz rows (what another program on a robot's computer "
                             "does to a subscriber's tail, reproducibly)")
    parser.add_argument("--orchestra-python", default=None, metavar="PYTHON",
                        help="run orchestra's roles with this interpreter (e.g. the ROS 1 "
                             "one, /usr/bin/python3: the same interpreter build on both "
                             "sides; it must be this one's minor version)")
    parser.add_argument("--cpu", type=int, default=None, help="(child roles) run on this CPU")
    opts = parser.parse_args()
    global IMPL
    IMPL = opts.impl
    if opts.cpu is not None:
        os.sched_setaffinity(0, {opts.cpu})  # before any thread exists: all inherit it
    if opts.role == "sub":
        return role_sub(opts.kind, opts.count, opts.burst)
    if opts.role == "pub":
        return role_pub(opts.kind, opts.count, opts.burst, opts.gap)
    if opts.role == "multi_sub":
        return role_multi_sub(opts.topics.split(","))
    if opts.role == "phase_pub":
        return role_phase_pub(opts.topics.split(","), [float(x) for x in opts.phases.split(",")],
                              opts.count, opts.gap, opts.subscribers)
    if opts.role == "service":
        return role_service()
    if opts.role == "client":
        return role_client(opts.calls, opts.persistent_calls)
    if opts.role == "raw_server":
        return role_raw_server(opts.size, opts.count, opts.burst)

    scale = 0.25 if opts.quick else 1.0
    global CPUS, ORCHESTRA_PYTHON
    ORCHESTRA_PYTHON = opts.orchestra_python
    if opts.pin == "split" and hasattr(os, "sched_setaffinity") and len(os.sched_getaffinity(0)) >= 2:
        CPUS = SPLIT
        os.sched_setaffinity(0, {CPUS["master"]})  # before the master's threads start
    from orchestra.master import start_master
    master = start_master(host="127.0.0.1", port=0)
    env = dict(os.environ, ROS_MASTER_URI=master.uri, PYTHONUNBUFFERED="1")
    results: dict = {"pinning": describe_pinning(), "load_start": os.getloadavg()}
    plan = {"twist": (int(2000 * scale), int(5000 * scale), 48, 0.002),
            "image": (int(200 * scale), int(300 * scale), IMAGE_BYTES + 70, 0.01)}
    # --quick shortens the topic rows only: the issue-15 rows (service calls, 100 Hz p99)
    # keep their samples, a p99 of fewer than a few thousand messages being a handful of
    # the worst ones (and a 5,000-call round of persistent calls lasting 0.2 s)
    calls = opts.calls
    persistent_calls = opts.persistent_calls
    try:
        if opts.rows == "all":
            for kind, (count, burst, size, gap) in plan.items():
                results[kind] = bench_topic(env, kind, count, burst, gap)
                results[kind]["baseline"] = raw_baseline(size, count, burst, 10, gap)
            results["service"] = bench_service(env, calls, persistent_calls)
            results["service"]["baseline"] = raw_baseline(
                8, 1, 2, persistent_calls, 0)["calls_per_s"]
        import ros1
        if ros1.has_modules("rospy", "geometry_msgs.msg", "sensor_msgs.msg", "std_srvs.srv"):
            if opts.rows == "all":
                results["ros1"] = {}
                for kind, (count, burst, _, gap) in plan.items():
                    for pub_impl, sub_impl in PAIRS[1:]:
                        results["ros1"][f"{kind} {pub_impl}->{sub_impl}"] = bench_topic(
                            env, kind, count, burst, gap, pub_impl, sub_impl)
            if opts.rows in ("all", "twist100"):
                with contenders(opts.contend):
                    results["twist100"] = twist100_rounds(env, opts.twist100_count, opts.rounds)
                results["twist100"]["contend"] = opts.contend
            if opts.rows in ("all", "service"):
                results["services"] = service_rounds(env, calls, persistent_calls, opts.rounds)
        else:
            ros1.skip("rospy comparisons", "rospy (with geometry_msgs, sensor_msgs, std_srvs)")
    finally:
        master.shutdown()
    results["load_end"] = os.getloadavg()
    if opts.json:
        print(json.dumps(results, indent=2))
        return
    if opts.rows == "all":
        print_baseline(results, plan)
    if "ros1" in results:
        print_ros1(results, plan)
    if "twist100" in results:
        print_twist100(results["twist100"])
    if "services" in results:
        print_services(results["services"])
    print(results["pinning"])
    print(f"orchestra's roles ran on {opts.orchestra_python or sys.executable}")
    print(f"load average (1 min) {results['load_start'][0]:.2f} at the start, "
          f"{results['load_end'][0]:.2f} at the end, on {os.cpu_count()} cores")


PAIRS = [("orchestra", "orchestra"), ("rospy", "rospy"), ("orchestra", "rospy"),
         ("rospy", "orchestra")]
SHORT = {"orchestra": "orch", "rospy": "rospy"}


def pair_name(pair: tuple[str, str]) -> str:
    return f"{SHORT[pair[0]]}->{SHORT[pair[1]]}"


def round_order(i: int) -> list[tuple[str, str]]:
    """The pairs in round ``i``'s order: rotated each round, so no pair always runs
    right after the same one (or first, when the machine is quietest)."""
    k = i % len(PAIRS)
    return PAIRS[k:] + PAIRS[:k]


#: the two comparisons of the 100 Hz rows: (name, the pair that differs from rospy->rospy,
#: the side it differs on)
TWIST100 = (("subscriber", ("rospy", "orchestra")), ("publisher", ("orchestra", "rospy")))


def twist100_rounds(env: dict, count: int, rounds: int, period: float = 0.01) -> dict:
    """Twist at 100 Hz (a robot's cmd_vel), latency only. Each comparison runs its two pairs
    AT ONCE, their messages ``period/2`` apart on absolute times: orchestra's subscriber
    and rospy's, both fed by one rospy publisher process (one topic each); then orchestra's
    publisher and rospy's, both read by one rospy subscriber process. Both pairs of a
    comparison so see the same machine, sampled alternately every 5 ms, instead of two runs
    seconds apart whose p99s differ by what else ran then (on a shared machine that
    difference was 0.2-6x). The phases swap every round and each period starts up to
    ``JITTER`` late at random; each round's p99 ratio and the pooled one are kept."""
    per_round: list[dict] = []
    pooled: dict[str, dict[str, list[float]]] = {}
    for i in range(rounds):
        got: dict = {"load": os.getloadavg()[0]}
        for name, (pub_impl, sub_impl) in TWIST100[i % 2:] + TWIST100[:i % 2]:
            pair, base = pair_name((pub_impl, sub_impl)), pair_name(("rospy", "rospy"))
            topics = {pair: "/t100_orch", base: "/t100_rospy"}
            phases = {pair: 0.0, base: period / 2} if i % 2 else {pair: period / 2, base: 0.0}
            if name == "subscriber":  # one rospy publisher, a subscriber of each
                subs = [(sub_impl, [topics[pair]]), ("rospy", [topics[base]])]
                pubs = [("rospy", [topics[pair], topics[base]], [phases[pair], phases[base]])]
            else:  # a publisher of each, one rospy subscriber
                subs = [("rospy", [topics[pair], topics[base]])]
                pubs = [(pub_impl, [topics[pair]], [phases[pair]]),
                        ("rospy", [topics[base]], [phases[base]])]
            samples = phase_run(env, subs, pubs, count, period)
            got[name] = {k: summarize(samples[t]) for k, t in topics.items()}
            for k, t in topics.items():
                pooled.setdefault(name, {}).setdefault(k, []).extend(samples[t])
        per_round.append(got)
    return {"rounds": per_round,
            "pooled": {name: {k: summarize(v) for k, v in pairs.items()}
                       for name, pairs in pooled.items()}}


@contextlib.contextmanager
def contenders(count: int):
    """``count`` busy-looping processes on the subscribers' CPU, each in its own session (as
    an unrelated program would be), for the duration of the block."""
    cpu = ["taskset", "-c", str(CPUS["sub"])] if CPUS and shutil.which("taskset") else []
    procs = [subprocess.Popen([*cpu, sys.executable, "-c", "while True: pass"],
                              start_new_session=True) for _ in range(count)]
    try:
        yield
    finally:
        for proc in procs:
            proc.kill()
            proc.wait()


def phase_run(env: dict, subs: list[tuple[str, list[str]]],
              pubs: list[tuple[str, list[str], list[float]]], count: int,
              period: float) -> dict[str, list[float]]:
    """Subscriber processes, then publisher processes sending on phases of one shared
    start time; every sample of every topic."""
    procs: list[subprocess.Popen] = []
    try:
        sub_procs = []
        for impl, topics in subs:
            sub_procs.append(child(env, "multi_sub", "--topics", ",".join(topics), impl=impl))
            procs.append(sub_procs[-1])
        for proc in sub_procs:
            read(proc, "ready")
        pub_procs = []
        for impl, topics, phases in pubs:
            pub_procs.append(child(env, "phase_pub", "--topics", ",".join(topics), "--phases",
                                   ",".join(map(str, phases)), "--count", str(count),
                                   "--gap", str(period), impl=impl))
            procs.append(pub_procs[-1])
        for proc in pub_procs:
            read(proc, "connected")
        t0 = now() + 0.3  # every publisher has its connections: a common start
        seed = random.randrange(1 << 30)
        for proc in pub_procs:
            tell(proc, f"{t0!r} {seed}")
        for proc in pub_procs:
            read(proc, "latency_sent")
        samples: dict[str, list[float]] = {}
        for proc in sub_procs:
            tell(proc, "latency done")
            samples.update(read(proc, "samples")["samples"])
        for proc in pub_procs:
            tell(proc)
        for proc in procs:
            proc.wait(15)
        return samples
    finally:
        for proc in procs:
            if proc.poll() is None:
                proc.kill()
                proc.wait()


def service_rounds(env: dict, calls: int, persistent_calls: int, rounds: int) -> dict:
    """Service calls/s of every client->service pair in each of ``rounds`` interleaved
    rounds (the shared machine's load swings a single run by 2x: medians and the spread)."""
    per_round: list[dict] = []
    for i in range(rounds):
        got = {"load": os.getloadavg()[0]}
        for cli_impl, svc_impl in round_order(i):
            got[pair_name((cli_impl, svc_impl))] = bench_service(
                env, calls, persistent_calls, svc_impl, cli_impl)
        per_round.append(got)
    return {"rounds": per_round}


def bench_service(env: dict, calls: int, persistent_calls: int, svc_impl: str = "orchestra",
                  cli_impl: str = "orchestra") -> dict:
    svc = child(env, "service", impl=svc_impl)
    try:
        read(svc, "ready")
        cli = child(env, "client", "--calls", str(calls), "--persistent-calls",
                    str(persistent_calls), impl=cli_impl)
        got = read(cli, "calls_per_s")
        cli.wait(30)
        tell(svc)
        svc.wait(15)
    finally:
        for proc in (svc, locals().get("cli")):
            if proc is not None and proc.poll() is None:
                proc.kill()
                proc.wait()
    return {**got["calls_per_s"], "client_cpu_us": got["client_cpu_us"]}


def describe_pinning() -> str:
    if not CPUS:
        return "unpinned (placement left to the scheduler)"
    return (f"pinned: publishers and clients on CPU {CPUS['pub']}, subscribers, services and "
            f"the master on CPU {CPUS['sub']}")


def spread(values: list[float]) -> str:
    """``median [min-max]`` of per-round ratios."""
    return f"{statistics.median(values):.2f}x [{min(values):.2f}-{max(values):.2f}]"


def print_baseline(results: dict, plan: dict) -> None:
    """orchestra->orchestra next to the same bytes over a bare socket."""
    print(f"{'':36}{'orchestra':>14}{'raw socket':>14}{'ratio':>9}")
    for kind, label in (("twist", "Twist"), ("image", "Image 640x480")):
        r = results[kind]
        base = r["baseline"]
        for key, name in (("median_us", "latency median (us)"), ("p99_us", "latency p99 (us)")):
            print(f"{label + ' ' + name:36.36}{r['latency'][key]:14.1f}{base['latency'][key]:14.1f}"
                  f"{r['latency'][key] / base['latency'][key]:9.1f}")
        print(f"{label + ' msgs/s':36.36}{r['throughput']['msgs_per_s']:14.0f}"
              f"{base['throughput']['msgs_per_s']:14.0f}"
              f"{base['throughput']['msgs_per_s'] / r['throughput']['msgs_per_s']:9.1f}")
        print(f"{label + ' MB/s':36.36}{r['throughput']['mb_per_s']:14.1f}"
              f"{base['throughput']['mb_per_s']:14.1f}")
        print(f"{label + ' received/sent':36.36}{r['throughput']['received']:>14}"
              f"{plan[kind][1]:>14}")
    s = results["service"]
    for key in ("plain", "persistent"):
        print(f"{'service calls/s ' + key:36}{s[key]:14.0f}{s['baseline']:14.0f}"
              f"{s['baseline'] / s[key]:9.1f}")
    print("ratio = how many times slower than the bare-socket baseline (lower is better)")


def print_ros1(results: dict, plan: dict) -> None:
    """orchestra->orchestra next to rospy->rospy and the mixed pairs (pub->sub)."""
    cols = [pair_name(p) for p in PAIRS]
    print(f"\n{'against real rospy (pub->sub)':36.36}" + "".join(f"{c:>14}" for c in cols)
          + f"{'rospy/orch':>12}")
    for kind, label in (("twist", "Twist"), ("image", "Image 640x480")):
        runs = [results[kind]] + [results["ros1"][f"{kind} {a}->{b}"] for a, b in PAIRS[1:]]
        for key, name, fmt, better_low in (
                ("median_us", "latency median (us)", "14.0f", True),
                ("p99_us", "latency p99 (us)", "14.0f", True),
                ("msgs_per_s", "msgs/s", "14.0f", False),
                ("mb_per_s", "MB/s", "14.1f", False),
                ("received", "received of sent", "14d", False)):
            part = "latency" if key.endswith("_us") else "throughput"
            values = [r[part][key] for r in runs]
            line = f"{label + ' ' + name:36.36}" + "".join(format(v, fmt) for v in values)
            if key == "received":
                line += f"{plan[kind][1]:>12}"
            elif values[0] and values[1]:
                ratio = values[1] / values[0] if better_low else values[0] / values[1]
                line += f"{ratio:11.1f}x"
            print(line)
    print("rospy/orch = how many times orchestra->orchestra beats rospy->rospy (higher: "
          "orchestra better)")


def print_twist100(data: dict) -> None:
    """The 100 Hz rows: for each comparison, both pairs' pooled medians and p99s, each
    round's p99s, and the p99 ratio against rospy->rospy per round (median and range) and
    pooled."""
    rounds, pooled = data["rounds"], data["pooled"]
    base = "rospy->rospy"
    busy = f", {data['contend']} busy process(es) on the subscribers' CPU" \
        if data.get("contend") else ""
    print(f"\nTwist 100 Hz latency, the two pairs of a comparison run at once, 5 ms apart "
          f"({len(rounds)} rounds{busy})")
    for name, pair in TWIST100:
        col = pair_name(pair)
        print(f"{'  which ' + name + ' (us)':36}{col:>14}{base:>14}{'ratio':>9}")
        for key, label in (("median_us", "median, pooled"), ("p99_us", "p99, pooled"),
                           ("late_pct", "% later than 1 ms, pooled")):
            a, b = pooled[name][col][key], pooled[name][base][key]
            print(f"{'    ' + label:36}{a:14.2f}{b:14.2f}{b / a if a else float('nan'):8.2f}x"
                  if key == "late_pct" else f"{'    ' + label:36}{a:14.0f}{b:14.0f}{b / a:8.2f}x")
        for i, r in enumerate(rounds, 1):
            a, b = r[name][col]["p99_us"], r[name][base]["p99_us"]
            label = f"    p99 round {i} (load {r['load']:.1f})"
            print(f"{label:36}{a:14.0f}{b:14.0f}{b / a:8.2f}x")
        late = [(r[name][col]["late_pct"], r[name][base]["late_pct"]) for r in rounds]
        print(f"    % later than 1 ms per round ({col} / {base}): "
              + ", ".join(f"{a:.1f}/{b:.1f}" for a, b in late))
        ratios = [r[name][base]["p99_us"] / r[name][col]["p99_us"] for r in rounds]
        print(f"    {col}: p99 of rospy->rospy / p99 of {col} per round {spread(ratios)}, "
              f"pooled {pooled[name][base]['p99_us'] / pooled[name][col]['p99_us']:.2f}x "
              f"({rounds[0][name][col]['n']} messages per pair and round; >= 1.0x: no worse "
              f"than rospy)")


def print_services(data: dict) -> None:
    """Service calls/s per pair: medians of the rounds, each round, and orch->orch over
    rospy->rospy per round (median and range); the client's CPU per call."""
    cols = [pair_name(p) for p in PAIRS]
    rounds = data["rounds"]
    print(f"\n{'service calls/s (client->service)':36.36}" + "".join(f"{c:>14}" for c in cols))
    for key in ("plain", "persistent"):
        print(f"{key + ', median of rounds':36}"
              + "".join(f"{statistics.median(r[c][key] for r in rounds):14.0f}" for c in cols))
        for i, r in enumerate(rounds, 1):
            label = f"  round {i} (load {r['load']:.1f})"
            print(f"{label:36}"
                  + "".join(f"{r[c][key]:14.0f}" for c in cols))
        ratios = [r["orch->orch"][key] / r["rospy->rospy"][key] for r in rounds]
        print(f"  orch->orch / rospy->rospy per round {spread(ratios)}")
    for key in ("plain", "persistent"):
        print(f"{'client CPU per call (us), ' + key:36.36}"
              + "".join(f"{statistics.median(r[c]['client_cpu_us'][key] for r in rounds):14.1f}"
                        for c in cols))
    print(f"({len(rounds)} interleaved rounds, pair order rotated each round)")


if __name__ == "__main__":
    main()
