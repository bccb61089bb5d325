#!/usr/bin/env python3
"""orchestra's ROS 1 layer vs Debian's real rospy: ``import rospy`` and exec -> init_node.

Two figures, each as the median of interleaved rounds (real, layer, real, layer...), every
sample a fresh process:

- **import**: the time ``import rospy`` takes inside the process (perf_counter around the
  statement; interpreter start-up and site/sitecustomize are before it). Also reported: the
  whole process (exec to exit) for a script that only imports rospy.
- **exec -> init_node**: wall time from just before the parent starts the process to the
  moment ``rospy.init_node(...)`` returns in it (the child prints ``time.time()``; parent
  and child read the same clock). Both sides register with the same master (orchestra's,
  in this process), so the master is not what is compared.

The layer's side runs the way orchestra runs a node: the interpreter orchestra runs on,
with ``orchestra/ros1/site`` on PYTHONPATH (``orchestra.ros1.activation.layer_env``).

    python bench/bench_rospy_layer.py            # 15 rounds
    python bench/bench_rospy_layer.py --quick    # 5 rounds
"""
from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import ros1  # noqa: E402

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

IMPORT_CODE = ("import time\nt0 = time.perf_counter()\nimport rospy\n"
               "print(time.perf_counter() - t0)\n")
INIT_CODE = ("import rospy\nimport time\nrospy.init_node('bench_init', anonymous=True, "
             "disable_signals=True)\nprint(time.time())\n")


def layer_env(master_uri: str) -> dict[str, str]:
    sys.path.insert(0, REPO)
    from orchestra.ros1.activation import layer_env as activation_env

    env = dict(os.environ, ROS_MASTER_URI=master_uri, PYTHONPATH=REPO)
    env.pop("ROS_NAMESPACE", None)
    # Debian's rospy runs from byte-compiled files; with PYTHONDONTWRITEBYTECODE inherited
    # (some shells set it) the layer side compiled its modules in every process (~30 ms of
    # a ~90 ms exec->init_node: 0.80x instead of 0.37x)
    env.pop("PYTHONDONTWRITEBYTECODE", None)
    env.update(activation_env(env))
    return env


def run(python: str, code: str, env: dict[str, str]) -> tuple[float, str]:
    """(wall seconds from exec to exit, the child's stdout)."""
    start = time.time()
    proc = subprocess.run([python, "-c", code], env=env, capture_output=True, text=True,
                          timeout=120)
    wall = time.time() - start
    if proc.returncode != 0:
        raise RuntimeError(f"{python} failed: {proc.stderr.strip()[-600:]}")
    return wall, proc.stdout.strip()


def exec_to_init(python: str, env: dict[str, str]) -> float:
    start = time.time()
    proc = subprocess.run([python, "-c", INIT_CODE], env=env, capture_output=True, text=True,
                          timeout=120)
    if proc.returncode != 0:
        raise RuntimeError(f"{python} failed: {proc.stderr.strip()[-600:]}")
    return float(proc.stdout.strip().splitlines()[-1]) - start


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--rounds", type=int, default=None)
    args = parser.parse_args()
    rounds = args.rounds or (5 if args.quick else 15)
    if not ros1.has_modules("rospy"):
        ros1.skip("rospy comparison", f"rospy under {ros1.ROS1_PYTHON}")
        return

    sys.path.insert(0, REPO)
    from orchestra.master import start_master

    master = start_master(host="127.0.0.1", port=0)
    try:
        real_env = ros1.base_env(ROS_MASTER_URI=master.uri)
        ours_env = layer_env(master.uri)
        sides = {"real rospy": (ros1.ROS1_PYTHON, real_env),
                 "orchestra layer": (sys.executable, ours_env)}
        # warm the file cache of both sides once; not counted
        for python, env in sides.values():
            run(python, IMPORT_CODE, env)
            exec_to_init(python, env)
        samples: dict[str, dict[str, list[float]]] = {
            side: {"import": [], "import process": [], "exec->init_node": []} for side in sides}
        for _ in range(rounds):
            for side, (python, env) in sides.items():
                wall, out = run(python, IMPORT_CODE, env)
                samples[side]["import"].append(float(out.splitlines()[-1]))
                samples[side]["import process"].append(wall)
                samples[side]["exec->init_node"].append(exec_to_init(python, env))
    finally:
        master.shutdown()

    print(f"rospy layer vs real rospy, median of {rounds} interleaved rounds "
          f"({ros1.load_average()})")
    print(f"{'figure':<20}{'real rospy':>14}{'layer':>14}{'layer/real':>12}")
    for figure in ("import", "import process", "exec->init_node"):
        real = statistics.median(samples["real rospy"][figure])
        ours = statistics.median(samples["orchestra layer"][figure])
        print(f"{figure:<20}{real * 1000:>11.1f} ms{ours * 1000:>11.1f} ms{ours / real:>11.2f}x")


if __name__ == "__main__":
    main()
