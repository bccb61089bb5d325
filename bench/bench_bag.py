#!/usr/bin/env python3
"""Bag speed: record throughput and play timing accuracy, orchestra next to real rosbag.

    python bench/bench_bag.py            # full run (~2 minutes)
    python bench/bench_bag.py --quick    # fewer messages and rounds

Record: one orchestra publisher process sends COUNT messages as fast as it can (its queue
holds them all, so nothing is dropped on its side) to one recorder process, either
``orchestra bag record`` or Debian's ``rosbag record`` (C++), stopped with SIGINT once the
burst is over. Each recorder stamps a message when it receives it, so the recorded stamps
give its rate: msgs/s = (kept - 1) / (last stamp - first stamp), MB/s the same with the
payload bytes; "kept" is how many of the COUNT reached the bag (rosbag record subscribes
with a queue of 100 and drops what overflows it in a burst). Twist (48 bytes) and a 640x480 rgb8 Image
(921,600 bytes).

Play: a bag of 3 s at 100 Hz is played by ``orchestra bag play`` and by ``rosbag play``
(both ``--wait-for-subscribers``) to one subscriber process that notes each arrival on
CLOCK_REALTIME; the timing error of message i is |(arrival_i - arrival_0) - (stamp_i -
stamp_0)|: median, p95 and max, and the error of the whole span.

Pinning, the same for both sides: the recorder process (and its children) runs on one CPU
and the publisher on another (``taskset -c``; ``--cpus REC,PUB``, default the last CPU and
CPU 0), so neither tool gets more cores than the other and the publisher, which is the
same for both, does not compete with the recorder for its CPU. The recorder's CPU time
(user+sys, from ``wait4``, its children included) is printed per round.

Rounds interleave the two tools; medians over rounds are printed. The master is orchestra's,
in this process, and not on any measured path. Real rosbag is skipped with one line when
it is missing.
"""
from __future__ import annotations

import argparse
import json
import os
import shutil
import signal
import statistics
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import ros1  # noqa: E402

HERE = os.path.abspath(__file__)
NS = 1_000_000_000
#: ``taskset -c CPU`` prefixes for the recorder and the publisher (empty: not pinned)
PIN_REC: list[str] = []
PIN_PUB: list[str] = []


# --- child roles ------------------------------------------------------------------------------

def role_pub(kind: str, count: int) -> None:
    import orchestra.node as rospy
    from orchestra.node.msg import get_message_class
    cls = get_message_class("geometry_msgs/Twist" if kind == "twist" else "sensor_msgs/Image")
    msg = cls()
    if kind == "image":
        msg.height, msg.width, msg.encoding, msg.step = 480, 640, "rgb8", 640 * 3
        msg.data = bytes(640 * 480 * 3)
    blob = bytes(msg.serialize_bytes())

    class Serialized(cls):  # type: ignore[valid-type, misc]
        """The one message, serialized once: the publisher's cost per message is only its
        socket write, so the burst outruns either recorder and the recorder sets the pace
        (serializing 300 images in the publishing thread starved the sending thread of the
        GIL for 5 ms at a time)."""
        __slots__ = ()

        def serialize_bytes(self) -> bytes:
            return blob
    msg = Serialized()
    rospy.init_node("bench_pub", argv=[], anonymous=True)
    pub = rospy.Publisher("/bench", cls, queue_size=count + 10)
    print(json.dumps({"ready": True}), flush=True)
    while pub.get_num_connections() < 1 and not rospy.is_shutdown():
        time.sleep(0.005)
    for _ in range(count):
        pub.publish(msg)
    print(json.dumps({"sent": count}), flush=True)
    rospy.spin()


def role_sub(count: int) -> None:
    import orchestra.node as rospy
    arrivals: list[float] = []

    def on(_msg) -> None:
        arrivals.append(time.time())
        if len(arrivals) == count:
            print(json.dumps({"arrivals": arrivals}), flush=True)
    rospy.init_node("bench_sub", argv=[], anonymous=True)
    rospy.Subscriber("/timed", rospy.AnyMsg, on, queue_size=0)
    print(json.dumps({"ready": True}), flush=True)
    rospy.spin()


# --- the driver -------------------------------------------------------------------------------

def child(env: dict, *args: str, pin: list[str] | None = None) -> subprocess.Popen:
    return subprocess.Popen([*(pin or []), sys.executable, HERE, *args], env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)


def read(proc: subprocess.Popen, key: str, timeout: float = 120) -> dict:
    deadline = time.monotonic() + timeout
    assert proc.stdout is not None
    while time.monotonic() < deadline:
        line = proc.stdout.readline()
        if not line:
            raise RuntimeError(f"child ended before sending {key}")
        try:
            obj = json.loads(line)
        except ValueError:
            continue
        if key in obj:
            return obj
    raise RuntimeError(f"no {key} within {timeout}s")


def subscribed(master_uri: str, topic: str) -> bool:
    import xmlrpc.client
    _c, _m, (_p, subs, _s) = xmlrpc.client.ServerProxy(master_uri).getSystemState("/bench")
    return any(t == topic and n for t, n in subs)


def wait(pred, timeout: float = 30) -> None:
    deadline = time.monotonic() + timeout
    while not pred():
        if time.monotonic() > deadline:
            raise RuntimeError("timed out")
        time.sleep(0.02)


def stop(proc: subprocess.Popen) -> None:
    ros1.kill_tree(proc.pid)
    proc.wait()


def interrupt_and_wait(pid: int) -> float:
    """SIGINT to a recorder and its children (rosbag's wrapper runs the C++ recorder as a
    child), then wait for all of them: the bag is complete only when the last one exits.
    Returns the recorder's CPU seconds (user + sys, the children it waited for included)."""
    import psutil
    try:
        parent = psutil.Process(pid)
        kids = parent.children(recursive=True)
    except psutil.NoSuchProcess:
        return float("nan")
    for proc in [*kids, parent]:
        try:
            proc.send_signal(signal.SIGINT)
        except psutil.NoSuchProcess:
            pass
    psutil.wait_procs(kids, timeout=120)
    _pid, _status, usage = os.wait4(pid, 0)
    return usage.ru_utime + usage.ru_stime


def recorder_argv(tool: str, out: str) -> tuple[list[str], dict | None]:
    if tool == "orchestra":
        return [sys.executable, "-m", "orchestra", "bag", "record", "-q", "-O", out,
                "/bench"], None
    return [ros1.ROS1_PYTHON, os.path.join(ros1.ROS1_BIN, "rosbag"), "record", "-q", "-O",
            out, "/bench"], {}


def bench_record(env: dict, tool: str, kind: str, count: int, tmp: str) -> dict:
    from orchestra.bag.reader import BagReader
    out = os.path.join(tmp, f"{tool}_{kind}.bag")
    if os.path.exists(out):
        os.unlink(out)
    argv, ros_env = recorder_argv(tool, out)
    renv = env if ros_env is None else ros1.base_env(ROS_MASTER_URI=env["ROS_MASTER_URI"])
    rec = subprocess.Popen([*PIN_REC, *argv], env=renv, stdout=subprocess.DEVNULL,
                           stderr=subprocess.DEVNULL)
    pub = None
    cpu = float("nan")
    try:
        wait(lambda: subscribed(env["ROS_MASTER_URI"], "/bench"))
        pub = child(env, "--role", "pub", kind, str(count), pin=PIN_PUB)
        read(pub, "sent", timeout=300)
        # the recorder drains what is in flight (a bench, not a test: a plain wait)
        time.sleep(2.0 + count * (1e6 if kind == "image" else 100) / 50e6)
        cpu = interrupt_and_wait(rec.pid)
    finally:
        if pub is not None:
            stop(pub)
        if rec.returncode is None and rec.poll() is None:
            stop(rec)
    with BagReader(out) as reader:
        stamps, size = [], 0
        for _c, stamp, data in reader.messages():
            stamps.append(stamp)
            size += len(data)
    span = (stamps[-1] - stamps[0]) / NS if len(stamps) > 1 else float("nan")
    return {"count": len(stamps), "msgs": (len(stamps) - 1) / span,
            "mbs": size * (len(stamps) - 1) / len(stamps) / span / 1e6, "cpu_s": cpu}


def make_timed_bag(path: str, hz: int = 100, seconds: int = 3) -> int:
    import struct

    from orchestra.bag.writer import BagWriter
    w = BagWriter(path).open()
    conn = w.add_connection("/timed", {
        "type": "std_msgs/String", "md5sum": "992ce8a1687cec8c8bd883ec73ca41d1",
        "message_definition": "string data\n", "callerid": "/bench", "latching": "0"})
    n = hz * seconds + 1
    for i in range(n):
        text = f"n {i}".encode()
        w.write(conn, 1_700_000_000 * NS + i * NS // hz, struct.pack("<I", len(text)) + text)
    w.close()
    return n


def bench_play(env: dict, tool: str, bag: str, n: int, hz: int) -> dict:
    sub = child(env, "--role", "sub", str(n))
    player = None
    try:
        read(sub, "ready")
        wait(lambda: subscribed(env["ROS_MASTER_URI"], "/timed"))
        if tool == "orchestra":
            argv = [sys.executable, "-m", "orchestra", "bag", "play", "-q", "-d", "0",
                    "--wait-for-subscribers", bag]
            penv = env
        else:
            argv = [ros1.ROS1_PYTHON, os.path.join(ros1.ROS1_BIN, "rosbag"), "play", "-q",
                    "-d", "0", "--wait-for-subscribers", bag]
            penv = ros1.base_env(ROS_MASTER_URI=env["ROS_MASTER_URI"])
        player = subprocess.Popen(argv, env=penv, stdout=subprocess.DEVNULL,
                                  stderr=subprocess.DEVNULL)
        arrivals = read(sub, "arrivals", timeout=60)["arrivals"]
    finally:
        sub.send_signal(signal.SIGINT)  # unregisters: no stale subscriber for the next round
        try:
            sub.wait(timeout=10)
        except subprocess.TimeoutExpired:
            stop(sub)
        if player is not None:
            player.wait(timeout=30)
    errors = sorted(abs((a - arrivals[0]) - i / hz) for i, a in enumerate(arrivals))
    span = arrivals[-1] - arrivals[0]
    return {"median_ms": statistics.median(errors) * 1e3,
            "p95_ms": errors[int(0.95 * (len(errors) - 1))] * 1e3, "max_ms": errors[-1] * 1e3,
            "span_err_pct": 100 * abs(span - (n - 1) / hz) / ((n - 1) / hz)}


def pin(spec: str) -> None:
    """Set the recorder's and the publisher's ``taskset`` prefixes from ``--cpus``."""
    if spec == "none" or not shutil.which("taskset"):
        return
    cpus = sorted(os.sched_getaffinity(0))
    rec, pub = (int(c) for c in spec.split(",")) if spec else (cpus[-1], cpus[0])
    PIN_REC[:] = ["taskset", "-c", str(rec)]
    PIN_PUB[:] = ["taskset", "-c", str(pub)]


def med(rows: list[dict], key: str) -> float:
    return statistics.median(r[key] for r in rows)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--rounds", type=int, help="rounds (default 5, --quick 1)")
    parser.add_argument("--only", choices=("twist", "image", "play"),
                        help="run one row only (A/B rounds of the image row)")
    parser.add_argument("--cpus", default="",
                        help="REC,PUB: the CPUs of the recorder and the publisher "
                             "(default: the last CPU and CPU 0; 'none': not pinned)")
    parser.add_argument("--role", nargs="+", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.role:
        if args.role[0] == "pub":
            role_pub(args.role[1], int(args.role[2]))
        else:
            role_sub(int(args.role[1]))
        return
    from orchestra.master import start_master
    rounds = args.rounds or (1 if args.quick else 5)
    pin(args.cpus)
    counts = {"twist": 5000 if args.quick else 20000, "image": 100 if args.quick else 300}
    tools = ["orchestra"]
    if ros1.tool("rosbag") and ros1.has_modules("rosbag", "rospy"):
        tools.append("rosbag")
    else:
        ros1.skip("rosbag comparisons", "Debian's rosbag")
    master = start_master(host="127.0.0.1", port=0)
    env = dict(os.environ, ROS_MASTER_URI=master.uri, PYTHONUNBUFFERED="1")
    print(f"# bench_bag: {ros1.load_average()}, {rounds} round(s), recorder pinned "
          f"{' '.join(PIN_REC) or 'no'}, publisher pinned {' '.join(PIN_PUB) or 'no'}")
    results: dict[tuple[str, str], list[dict]] = {}
    try:
        with tempfile.TemporaryDirectory() as tmp:
            kinds = [k for k in ("twist", "image") if args.only in (None, k)]
            for i in range(rounds):
                for kind in kinds:
                    # alternate which tool goes first, so neither always meets a warmer cache
                    for tool in (tools if i % 2 == 0 else tools[::-1]):
                        row = bench_record(env, tool, kind, counts[kind], tmp)
                        print(f"# record {kind} {tool}: {row}", flush=True)
                        results.setdefault((f"record {kind}", tool), []).append(row)
            bag = os.path.join(tmp, "timed.bag")
            n = make_timed_bag(bag)
            for _ in range(rounds if args.only in (None, "play") else 0):
                for tool in tools:
                    row = bench_play(env, tool, bag, n, 100)
                    print(f"# play {tool}: {row}", flush=True)
                    results.setdefault(("play", tool), []).append(row)
    finally:
        master.shutdown()
    print("\n| record | " + " | ".join(tools) + " | ratio (orchestra/rosbag) |")
    print("|---|" + "---|" * (len(tools) + 1))
    for kind in kinds:
        rows = {t: results[(f"record {kind}", t)] for t in tools}
        cells = [f"{med(r, 'msgs'):,.0f} msg/s ({med(r, 'mbs'):.1f} MB/s), "
                 f"{min(x['count'] for x in r)}/{counts[kind]} kept, "
                 f"CPU {med(r, 'cpu_s'):.2f} s" for r in rows.values()]
        ratio = "-"
        if "rosbag" in rows:
            per_round = sorted(o["msgs"] / r["msgs"]
                               for o, r in zip(rows["orchestra"], rows["rosbag"], strict=True))
            ratio = (f"{med(rows['orchestra'], 'msgs') / med(rows['rosbag'], 'msgs'):.2f}x "
                     f"(per round {per_round[0]:.2f}-{per_round[-1]:.2f}x)")
        print(f"| {kind} ({counts[kind]} msgs) | " + " | ".join(cells) + f" | {ratio} |")
    if args.only not in (None, "play"):
        return
    print("\n| play 3 s at 100 Hz | " + " | ".join(tools) + " |")
    print("|---|" + "---|" * len(tools))
    for key, label in (("median_ms", "timing error, median"), ("p95_ms", "timing error, p95"),
                       ("max_ms", "timing error, max"), ("span_err_pct", "span error")):
        unit = "%" if key.endswith("pct") else " ms"
        print(f"| {label} | " + " | ".join(f"{med(results[('play', t)], key):.2f}{unit}"
                                           for t in tools) + " |")


if __name__ == "__main__":
    main()
