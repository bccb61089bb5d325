"""Message imports through orchestra's ROS 1 layer vs genpy's generated modules.

Each sample is a fresh process: the layer side is orchestra's interpreter with the layer's
site directory on PYTHONPATH (as a node started by ``orchestra launch`` gets it), the genpy
side is Debian's /usr/bin/python3 importing the genpy-generated packages. Sides alternate
sample by sample (interleaved); figures are medians. Two numbers per case:

  * ``import``: time of the import statement(s) inside the process (what a node pays on top
    of the interpreter start);
  * ``process``: the whole process, start to exit (includes the layer's ``sitecustomize``).

Run:  python bench/bench_msg_import.py [--quick] [--repeat N] [--json out.json]
(``import rospy`` and exec -> init_node are in bench_rospy_layer.py.)
"""
from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import time

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, REPO)
sys.path.insert(0, os.path.join(REPO, "bench"))

import ros1  # noqa: E402

from orchestra.ros1.activation import SITE_DIR  # noqa: E402

CASES = {
    "std_msgs String": "from std_msgs.msg import String\nString(data='x')",
    "geometry_msgs PoseStamped": "from geometry_msgs.msg import PoseStamped\nPoseStamped()",
    "sensor_msgs Image+CameraInfo": ("from sensor_msgs.msg import Image, CameraInfo\n"
                                     "Image(); CameraInfo()"),
    "nav_msgs Odometry": "from nav_msgs.msg import Odometry\nOdometry()",
    "std_srvs+actionlib_msgs": ("from std_srvs.srv import SetBool\n"
                                "from actionlib_msgs.msg import GoalStatusArray\n"
                                "SetBool._request_class(); GoalStatusArray()"),
}

TIMED = ("import time as _t\n_t0 = _t.perf_counter()\n{body}\n"
         "print(_t.perf_counter() - _t0)\n")


def _layer_env() -> dict[str, str]:
    env = {"PATH": os.environ.get("PATH", "/usr/bin:/bin"), "HOME": os.environ.get("HOME", "/tmp"),
           "LANG": "C.UTF-8", "PYTHONPATH": os.pathsep.join([SITE_DIR, REPO])}
    return env


def sample(argv: list[str], code: str, env: dict[str, str]) -> tuple[float, float]:
    """(import seconds, whole-process seconds) of one fresh process."""
    start = time.perf_counter()
    proc = subprocess.run([*argv, "-c", code], env=env, capture_output=True, text=True,
                          timeout=120)
    wall = time.perf_counter() - start
    if proc.returncode != 0:
        raise RuntimeError(f"{argv[0]} failed: {proc.stderr.strip()[-500:]}")
    return float(proc.stdout.strip().splitlines()[-1]), wall


def run(repeat: int) -> dict:
    genpy_ok = ros1.has_modules("genpy", "std_msgs.msg", "geometry_msgs.msg", "sensor_msgs.msg",
                                "nav_msgs.msg", "std_srvs.srv", "actionlib_msgs.msg")
    if not genpy_ok:
        ros1.skip("genpy side", f"genpy message packages under {ros1.ROS1_PYTHON}")
    results = {}
    for name, body in CASES.items():
        code = TIMED.format(body=body)
        layer, genpy = [], []
        # one warm-up each: the layer's definition cache and both sides' .pyc files
        sample([sys.executable], code, _layer_env())
        if genpy_ok:
            sample([ros1.ROS1_PYTHON], code, ros1.base_env())
        for _ in range(repeat):
            layer.append(sample([sys.executable], code, _layer_env()))
            if genpy_ok:
                genpy.append(sample([ros1.ROS1_PYTHON], code, ros1.base_env()))
        row = {"layer_import_ms": 1e3 * statistics.median(s[0] for s in layer),
               "layer_process_ms": 1e3 * statistics.median(s[1] for s in layer)}
        if genpy:
            row["genpy_import_ms"] = 1e3 * statistics.median(s[0] for s in genpy)
            row["genpy_process_ms"] = 1e3 * statistics.median(s[1] for s in genpy)
            row["import_ratio"] = row["layer_import_ms"] / row["genpy_import_ms"]
            row["process_ratio"] = row["layer_process_ms"] / row["genpy_process_ms"]
        results[name] = row
    return results


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="5 samples per side and case")
    parser.add_argument("--repeat", type=int, default=None)
    parser.add_argument("--json", default=None, help="also write the figures here")
    args = parser.parse_args()
    repeat = args.repeat or (5 if args.quick else 21)
    print(ros1.load_average())
    results = run(repeat)
    print(f"{'case':30s} {'layer import':>13s} {'genpy import':>13s} {'ratio':>6s}   "
          f"{'layer proc':>11s} {'genpy proc':>11s} {'ratio':>6s}")
    def cell(value: float | None, unit: str, width: int) -> str:
        return f"{value:{width}.{1 if unit == 'ms' else 2}f}{' ms' if unit == 'ms' else 'x'}" \
            if value is not None else " " * (width - 1) + "-" + (" " * 3 if unit == "ms" else " ")

    for name, r in results.items():
        print(f"{name:30s} {cell(r['layer_import_ms'], 'ms', 10)} "
              f"{cell(r.get('genpy_import_ms'), 'ms', 10)} {cell(r.get('import_ratio'), 'x', 5)}   "
              f"{cell(r['layer_process_ms'], 'ms', 8)} {cell(r.get('genpy_process_ms'), 'ms', 8)} "
              f"{cell(r.get('process_ratio'), 'x', 5)}")
    if args.json:
        with open(args.json, "w") as fh:
            json.dump({"repeat": repeat, "results": results}, fh, indent=2)


if __name__ == "__main__":
    main()
