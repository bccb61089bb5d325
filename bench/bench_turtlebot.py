#!/usr/bin/env python3
"""TurtleBot simulated bring-up: how long until it is useful, and how fast commands act.

Plain Python, no pytest. Each figure comes with a baseline measured the same way in the same
run, so ratios mean something on a busy machine:

1. bring-up: ``orchestra launch turtlebot_bringup minimal.launch`` (7 nodes, 2 nodelets,
   embedded master) until a client has received /odom and /diagnostics_agg, against the same
   launcher running a single-node launch file until that node's first message.
2. command latency: a Twist published on /cmd_vel_mux/input/teleop until /odom reports the
   velocity (client -> mux over TCPROS, mux -> base in-process, base tick, base -> client over
   TCPROS), against the base's tick period (the unavoidable part).
3. nodelet hop: a burst of Twists between two nodelets of one manager (the in-process bus)
   against the same burst over TCPROS between two processes (what two separate nodes pay),
   per message until the last one's callback ran.

usage: python3 bench/bench_turtlebot.py [--runs N] [--samples N]
"""
from __future__ import annotations

import argparse
import json
import os
import signal
import socket
import statistics
import subprocess
import sys
import tempfile
import textwrap
import threading
import time
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))
sys.path.insert(0, str(REPO / "packages" / "nodelet" / "src"))

TICK_PERIOD = 1.0 / 20.0  # kobuki_node/param/base.yaml update_rate

PROBE = textwrap.dedent('''
    import json, sys, threading, time
    from orchestra import node
    from orchestra.node.msg import get_message_class as M
    mode, samples = sys.argv[1], int(sys.argv[2])
    while True:
        try:
            node.init_node("bench_probe", anonymous=True)
            break
        except Exception:
            time.sleep(0.02)
    first = {}
    odom_v = []
    cond = threading.Condition()
    def mark(key):
        with cond:
            first.setdefault(key, time.time())
            cond.notify_all()
    def on_odom(m):
        mark("odom")
        with cond:
            odom_v.append((time.time(), m.twist.twist.linear.x))
            cond.notify_all()
    if mode == "single":
        node.Subscriber("/tf_static", M("tf2_msgs/TFMessage"), lambda m: mark("first"))
        keys = ["first"]
    else:
        node.Subscriber("/odom", M("nav_msgs/Odometry"), on_odom)
        node.Subscriber("/diagnostics_agg", M("diagnostic_msgs/DiagnosticArray"),
                        lambda m: mark("agg"))
        keys = ["odom", "agg"]
    with cond:
        cond.wait_for(lambda: all(k in first for k in keys), timeout=60)
    latencies = []
    if mode == "full" and samples:
        pub = node.Publisher("/cmd_vel_mux/input/teleop", M("geometry_msgs/Twist"))
        time.sleep(0.5)   # let the mux connect
        twist = M("geometry_msgs/Twist")(); twist.linear.x = 0.2
        for _ in range(samples):
            time.sleep(1.0)   # the base's 0.6 s watchdog has stopped it
            t0 = time.time()
            pub.publish(twist)
            with cond:
                ok = cond.wait_for(lambda: any(t > t0 and v > 0 for t, v in odom_v), timeout=5)
                if ok:
                    latencies.append(min(t for t, v in odom_v if t > t0 and v > 0) - t0)
                odom_v.clear()
    sys.stdout.write(json.dumps({"first": first, "latencies": latencies}) + "\\n")
    sys.stdout.flush()
    node.signal_shutdown("done")
''')

SINGLE = textwrap.dedent('''\
    <launch>
      <param name="robot_description"
             textfile="$(find turtlebot_description)/robots/kobuki_hexagons_asus_xtion_pro.urdf"/>
      <node pkg="robot_state_publisher" type="robot_state_publisher" name="robot_state_publisher"/>
    </launch>
''')


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def bring_up(launch_words: list[str], mode: str, samples: int, tmp: str) -> dict:
    """Start a launch and a probe at the same instant; seconds until the probe's first data."""
    env = {k: v for k, v in os.environ.items() if not k.startswith(("ROS_", "TURTLEBOT_"))}
    env.update(ROS_MASTER_URI=f"http://127.0.0.1:{free_port()}/", ROS_HOME=os.path.join(tmp, "ros"))
    probe = os.path.join(tmp, "probe.py")
    Path(probe).write_text(PROBE)
    t0 = time.time()
    launcher = subprocess.Popen([sys.executable, "-m", "orchestra", "launch", *launch_words],
                                env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                                start_new_session=True)
    try:
        out = subprocess.run([sys.executable, probe, mode, str(samples)], env=env,
                             capture_output=True, text=True, timeout=120)
        result = json.loads(out.stdout.strip().splitlines()[-1])
    finally:
        launcher.send_signal(signal.SIGINT)
        try:
            launcher.wait(timeout=30)
        except subprocess.TimeoutExpired:
            os.killpg(launcher.pid, signal.SIGKILL)
            launcher.wait()
    ready = max(result["first"].values()) - t0
    return {"ready": ready, "latencies": result["latencies"]}


SUB = textwrap.dedent('''
    import json, sys, threading, time
    from orchestra import node
    from orchestra.node.msg import get_message_class as M
    n = int(sys.argv[1])
    node.init_node("bench_sub", anonymous=True)
    times = []
    done = threading.Event()
    def cb(_m):
        times.append(time.perf_counter())
        if len(times) == n:
            done.set()
    node.Subscriber("/bench_twist", M("geometry_msgs/Twist"), cb, queue_size=n)
    sys.stdout.write("ready\\n"); sys.stdout.flush()
    done.wait(60)
    sys.stdout.write(json.dumps({"per_msg": (times[-1] - times[0]) / (n - 1)}) + "\\n")
    sys.stdout.flush()
    node.signal_shutdown("done")
''')


def nodelet_hop(tmp: str, n: int = 2000) -> tuple[float, float]:
    """(in-process bus, TCPROS between processes): microseconds per Twist in a burst."""
    from nodelet.local import LocalBus

    from orchestra import node
    from orchestra.master import start_master
    from orchestra.node.msg import get_message_class
    twist_cls = get_message_class("geometry_msgs/Twist")
    twist = twist_cls()
    twist.linear.x = 0.3

    bus = LocalBus()
    times: list[float] = []
    done = threading.Event()

    def cb(_msg):
        times.append(time.perf_counter())
        if len(times) == n:
            done.set()
    bus.subscribe("/cmd", twist._type, cb, queue_size=n)
    for _ in range(n):
        bus.publish("/cmd", twist)
    done.wait(30)
    local = (times[-1] - times[0]) / (n - 1) * 1e6

    master = start_master(host="127.0.0.1", port=0)
    env = {k: v for k, v in os.environ.items() if not k.startswith("ROS_")}
    env.update(ROS_MASTER_URI=master.uri, ROS_HOME=os.path.join(tmp, "ros"))
    os.environ["ROS_MASTER_URI"] = master.uri
    script = os.path.join(tmp, "sub.py")
    Path(script).write_text(SUB)
    sub = subprocess.Popen([sys.executable, script, str(n)], env=env, stdout=subprocess.PIPE,
                           text=True)
    try:
        sub.stdout.readline()
        node.init_node("bench_pub", anonymous=True, disable_signals=True)
        pub = node.Publisher("/bench_twist", twist_cls, queue_size=n)
        deadline = time.time() + 20
        while pub.get_num_connections() == 0 and time.time() < deadline:
            time.sleep(0.01)
        for _ in range(n):
            pub.publish(twist)
        remote = json.loads(sub.stdout.readline())["per_msg"] * 1e6
    finally:
        if sub.poll() is None:
            sub.wait(timeout=30)
        node.signal_shutdown("bench done")
        master.shutdown()
    return local, remote


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=3, help="bring-ups of each launch")
    parser.add_argument("--samples", type=int, default=5, help="command latency samples")
    opts = parser.parse_args()
    full, single, latencies = [], [], []
    with tempfile.TemporaryDirectory() as tmp:
        single_launch = os.path.join(tmp, "single.launch")
        Path(single_launch).write_text(SINGLE)
        for run in range(opts.runs):
            single.append(bring_up([single_launch], "single", 0, tmp)["ready"])
            result = bring_up(["turtlebot_bringup", "minimal.launch"], "full",
                              opts.samples if run == 0 else 0, tmp)
            full.append(result["ready"])
            latencies.extend(result["latencies"])
        local, remote = nodelet_hop(tmp)
    f, s = statistics.median(full), statistics.median(single)
    print(f"bring-up, median of {opts.runs}:")
    print(f"  minimal.launch (7 nodes) until /odom and /diagnostics_agg: {f:.2f} s")
    print(f"  baseline, one-node launch until its first message:        {s:.2f} s")
    print(f"  ratio: {f / s:.2f}x")
    if latencies:
        lat = statistics.median(latencies)
        print(f"command latency, teleop Twist -> /odom velocity, median of {len(latencies)}: "
              f"{lat * 1000:.1f} ms = {lat / TICK_PERIOD:.2f} base ticks ({TICK_PERIOD * 1000:.0f} ms)")
    print(f"Twist burst, per message: nodelet in-process bus {local:.1f} us, "
          f"TCPROS between two processes {remote:.1f} us (ratio {remote / local:.1f}x)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
