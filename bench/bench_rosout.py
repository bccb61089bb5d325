#!/usr/bin/env python3
"""rosout's cost: what the extra hop /rosout -> rosout -> /rosout_agg adds to a log message.

Every figure has a baseline measured in the same run, the same way: the very same logging
node and the very same counting subscriber, but the subscriber listens on /rosout directly
(no rosout process in between). Ratios (via rosout / direct) are what to compare between
machines.

    python bench/bench_rosout.py            # full run (~20 s)
    python bench/bench_rosout.py --quick

1. latency of ``loginfo`` -> subscriber callback at a steady 500 msg/s (median, p99), and
   how many messages arrived;
2. a burst of ``loginfo`` calls as fast as the node can make them: messages delivered per
   second (first to last arrival) and how many arrived (the node's /rosout publisher keeps
   the newest 100 per connection, like rospy's, so a burst may lose some on either path);
3. start-up: spawn -> /rosout subscription registered on the master, for the rosout script
   and, as baseline, a minimal orchestra.node process subscribing /rosout.

Latency = arrival wall time - the message's header stamp (set by the logging node from the
same wall clock).
"""
from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import threading
import time
import xmlrpc.client

HERE = os.path.abspath(__file__)
REPO = os.path.dirname(os.path.dirname(HERE))
ROSOUT = os.path.join(REPO, "packages", "rosout", "scripts", "rosout")


# ------------------------------------------------------------------ roles (child processes)

def role_counter(topic: str, count: int, out: str, warm_flag: str) -> None:
    """Subscribe ``topic``; flag the first warm-up message; record the measured ones."""
    import orchestra.node as node
    from orchestra.node.msg import get_message_class

    node.init_node("bench_counter", disable_rosout=True)
    arrivals: list[tuple[float, float]] = []
    done = threading.Event()

    def on_log(msg) -> None:
        now = time.time()
        if msg.msg.startswith("warm"):
            if not os.path.exists(warm_flag):
                open(warm_flag, "w").close()
            return
        arrivals.append((now, msg.header.stamp.to_sec()))
        if len(arrivals) >= count:
            done.set()

    node.Subscriber(topic, get_message_class("rosgraph_msgs/Log"), on_log, queue_size=0)
    deadline = time.monotonic() + 60
    # all of them, or nothing new for a second (a burst may lose some)
    while not done.wait(0.1) and time.monotonic() < deadline:
        if arrivals and time.time() - arrivals[-1][0] > 1.0:
            break
    with open(out, "w") as fh:
        json.dump(arrivals, fh)
    node.signal_shutdown("bench done")


def role_logger(count: int, rate: float, warm_flag: str) -> None:
    """Warm up until the counter hears us, then ``count`` loginfo calls (rate 0 = a burst)."""
    import orchestra.node as node

    node.init_node("bench_logger")
    deadline = time.monotonic() + 30
    while not os.path.exists(warm_flag) and time.monotonic() < deadline:
        node.loginfo("warm")
        time.sleep(0.02)
    time.sleep(0.2)
    start = time.monotonic()
    for i in range(count):
        node.loginfo("measured %d", i)
        if rate:
            wait = start + (i + 1) / rate - time.monotonic()
            if wait > 0:
                time.sleep(wait)
    time.sleep(1.0)          # let the writer threads drain before exit
    node.signal_shutdown("bench done")


def role_subscriber_only() -> None:
    """Start-up baseline: the least a Python node subscribing /rosout has to do."""
    import orchestra.node as node
    from orchestra.node.msg import get_message_class

    node.init_node("rosout", disable_rosout=True)
    node.Subscriber("/rosout", get_message_class("rosgraph_msgs/Log"), lambda m: None)
    node.spin()


# ------------------------------------------------------------------ measurements

def _child(env: dict, *args: str, **kwargs) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, HERE, *args], env=env, **kwargs)


def _start_rosout(env: dict, log_dir: str) -> subprocess.Popen:
    return subprocess.Popen([ROSOUT, "__name:=rosout", f"__log:={log_dir}/rosout-1.log"],
                            env=env, stdout=subprocess.DEVNULL)


def _wait_subscribed(master_uri: str, topic: str, node: str, timeout: float = 30) -> None:
    proxy = xmlrpc.client.ServerProxy(master_uri)
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        _, _, (_, subs, _) = proxy.getSystemState("/bench")
        if any(t == topic and node in nodes for t, nodes in subs):
            return
        time.sleep(0.005)
    raise SystemExit(f"{node} never subscribed {topic}")


def run_path(env: dict, via_rosout: bool, count: int, rate: float, tmp: str) -> dict:
    topic = "/rosout_agg" if via_rosout else "/rosout"
    tag = f"{'agg' if via_rosout else 'direct'}-{rate}"
    out, flag = os.path.join(tmp, tag + ".json"), os.path.join(tmp, tag + ".warm")
    rosout = _start_rosout(env, tmp) if via_rosout else None
    try:
        if rosout is not None:
            _wait_subscribed(env["ROS_MASTER_URI"], "/rosout", "/rosout")
        counter = _child(env, "--role", "counter", "--topic", topic, "--count", str(count),
                         "--out", out, "--flag", flag)
        logger = _child(env, "--role", "logger", "--count", str(count), "--rate", str(rate),
                        "--flag", flag, stdout=subprocess.DEVNULL)
        logger.wait(120)
        counter.wait(120)
    finally:
        if rosout is not None:
            rosout.terminate()
            rosout.wait(10)
    with open(out) as fh:
        arrivals = json.load(fh)
    result: dict = {"received": len(arrivals), "sent": count}
    if arrivals:
        latencies = sorted(a - s for a, s in arrivals)
        result["median_us"] = statistics.median(latencies) * 1e6
        result["p99_us"] = latencies[min(len(latencies) - 1, int(len(latencies) * 0.99))] * 1e6
        span = arrivals[-1][0] - arrivals[0][0]
        result["msg_per_s"] = (len(arrivals) - 1) / span if span > 0 else float("nan")
    return result


def startup(env: dict, via_rosout: bool, tmp: str, runs: int) -> float:
    times = []
    for _ in range(runs):
        t0 = time.perf_counter()
        proc = (_start_rosout(env, tmp) if via_rosout
                else _child(env, "--role", "subscriber_only"))
        try:
            _wait_subscribed(env["ROS_MASTER_URI"], "/rosout", "/rosout")
            times.append(time.perf_counter() - t0)
        finally:
            proc.terminate()
            proc.wait(10)
        time.sleep(0.2)       # its unregistration done before the next start
    return statistics.median(times)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--role", default=None)
    parser.add_argument("--topic", default="/rosout")
    parser.add_argument("--count", type=int, default=2000)
    parser.add_argument("--rate", type=float, default=0.0)
    parser.add_argument("--out", default="")
    parser.add_argument("--flag", default="")
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--json", action="store_true", help="Print one JSON document.")
    opts = parser.parse_args()
    if opts.role == "counter":
        return role_counter(opts.topic, opts.count, opts.out, opts.flag)
    if opts.role == "logger":
        return role_logger(opts.count, opts.rate, opts.flag)
    if opts.role == "subscriber_only":
        return role_subscriber_only()

    from orchestra.master import start_master

    scale = 0.25 if opts.quick else 1.0
    master = start_master(host="127.0.0.1", port=0)
    env = dict(os.environ, ROS_MASTER_URI=master.uri, PYTHONUNBUFFERED="1")
    results: dict = {}
    try:
        with tempfile.TemporaryDirectory() as tmp:
            steady, burst = int(2000 * scale), int(2000 * scale)
            for name, count, rate in (("steady_500hz", steady, 500.0), ("burst", burst, 0.0)):
                results[name] = {"direct": run_path(env, False, count, rate, tmp),
                                 "via_rosout": run_path(env, True, count, rate, tmp)}
            runs = 3 if opts.quick else 5
            results["startup_s"] = {"subscriber_only": startup(env, False, tmp, runs),
                                    "rosout": startup(env, True, tmp, runs)}
    finally:
        master.shutdown()
    if opts.json:
        print(json.dumps(results, indent=1))
        return
    for name in ("steady_500hz", "burst"):
        d, r = results[name]["direct"], results[name]["via_rosout"]
        print(f"{name}: received direct {d['received']}/{d['sent']}, "
              f"via rosout {r['received']}/{r['sent']}")
        for key, unit in (("median_us", "us"), ("p99_us", "us"), ("msg_per_s", "msg/s")):
            if key in d and key in r:
                print(f"  {key:10s} direct {d[key]:10.0f} {unit:5s} via rosout {r[key]:10.0f} "
                      f"{unit:5s} ratio {r[key] / d[key]:.2f}")
    s = results["startup_s"]
    print(f"startup to /rosout subscribed: minimal node {s['subscriber_only']:.2f} s, "
          f"rosout {s['rosout']:.2f} s, ratio {s['rosout'] / s['subscriber_only']:.2f}")


if __name__ == "__main__":
    main()
