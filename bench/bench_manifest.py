"""package.xml parsing: orchestra's ``packages/manifest.py`` against catkin_pkg's parser.

Issue 16 asks whether the well-kept library (catkin_pkg, what ROS's own tools use) should
replace ours; the index caches what it reads, so the cost matters only cold. Each side runs
in a process of its own (interleaved, medians over ``--repeat`` rounds) and reports:

  * import: the parser module imported (what a cold ``orchestra`` command pays once);
  * parse: every package.xml of the trees parsed once, in that process (first parse, cold);
  * whole: the process from start to end (interpreter start-up included).

Trees: ../shared/compat/ws (real ROS packages) and this repository's packages/.

Run:  python bench/bench_manifest.py [--repeat N]
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
TREES = [os.path.join(os.path.dirname(REPO), "shared", "compat", "ws"),
         os.path.join(REPO, "packages")]

CHILD = r"""
import json, os, sys, time
t0 = time.perf_counter()
if sys.argv[1] == "orchestra":
    from orchestra.packages.manifest import parse_manifest as parse
else:
    from catkin_pkg.package import parse_package as parse
t1 = time.perf_counter()
paths = json.loads(sys.argv[2])
for path in paths:
    parse(path)
t2 = time.perf_counter()
print(json.dumps({"import": t1 - t0, "parse": t2 - t1}))
"""


def manifests() -> list[str]:
    found = []
    for tree in TREES:
        for directory, dirs, files in os.walk(tree):
            dirs[:] = [d for d in dirs if not d.startswith(".")]
            if "package.xml" in files:
                found.append(os.path.join(directory, "package.xml"))
    return sorted(found)


def run(side: str, paths: list[str]) -> dict[str, float]:
    env = dict(os.environ, PYTHONPATH=REPO + os.pathsep + os.environ.get("PYTHONPATH", ""),
               PYTHONWARNINGS="ignore")
    start = time.perf_counter()
    out = subprocess.run([sys.executable, "-c", CHILD, side, json.dumps(paths)], env=env,
                         capture_output=True, text=True, check=True).stdout
    whole = time.perf_counter() - start
    return {**json.loads(out), "whole": whole}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=9)
    options = parser.parse_args()
    paths = manifests()
    try:
        import catkin_pkg  # noqa: F401
    except ImportError:
        sys.exit("catkin_pkg is not installed (pip install catkin_pkg): nothing to compare")
    results: dict[str, list[dict[str, float]]] = {"orchestra": [], "catkin_pkg": []}
    for _ in range(options.repeat):
        for side in ("orchestra", "catkin_pkg"):  # interleaved
            results[side].append(run(side, paths))
    print(f"{len(paths)} package.xml files, {options.repeat} rounds, medians (ms)")
    print(f"  {'':12} {'import':>9} {'parse':>9} {'whole':>9}")
    med = {side: {k: statistics.median(r[k] for r in rows) * 1e3 for k in rows[0]}
           for side, rows in results.items()}
    for side, m in med.items():
        print(f"  {side:12} {m['import']:9.1f} {m['parse']:9.1f} {m['whole']:9.1f}")
    o, c = med["orchestra"], med["catkin_pkg"]
    print(f"  catkin_pkg / orchestra: import x{c['import'] / o['import']:.2f}, "
          f"parse x{c['parse'] / o['parse']:.2f}, whole x{c['whole'] / o['whole']:.2f}")


if __name__ == "__main__":
    main()
