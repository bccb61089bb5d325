#!/usr/bin/env python3
"""How fast does orchestra resolve launch files? Ratios are measured in the same run.

1. The 80 real compat cases (../shared/compat) resolved in-process, against the per-case cost
   of ``orchestra launch --dump-plan --no-exec`` in a subprocess (what compare.py pays).
2. A synthetic tree generated into a temp dir: 1,000 nodes, 20,000 params, includes nested 30
   deep, every include path and many values going through ``$(find)`` and ``$(arg)``. Target:
   resolved in under 1 s.
3. ``$(find)`` cost per call once the package index is built (it must not re-crawl).

usage: python3 bench/bench_launch.py [--subprocess-samples N]
"""
from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
COMPAT = REPO.parent / "shared" / "compat"
sys.path.insert(0, str(REPO))

from orchestra.launch.interpreter import Interpreter, LoadOptions  # noqa: E402
from orchestra.names import load_mappings  # noqa: E402

DEPTH = 30
NODES = 1000
PARAMS_PER_NODE = 20


def _case_env(ws: str, extra: dict | None) -> dict[str, str]:
    env = {"PATH": os.environ.get("PATH", "/usr/bin:/bin"), "ROS_PACKAGE_PATH": ws,
           "ROS_DISTRO": "noetic", "LANG": "C.UTF-8"}
    env.update({k: v.replace("${WS}", ws) for k, v in (extra or {}).items()})
    return env


def _resolve(path: str, words: list[str]) -> None:
    interp = Interpreter(LoadOptions(args=load_mappings(words), no_exec=True))
    interp.load_file(path)
    interp.plan()


def bench_cases(samples: int) -> None:
    cases = json.loads((COMPAT / "cases.json").read_text())
    ws = str(COMPAT / "ws")
    jobs = []
    for case in cases:
        words = ["%s:=%s" % (k, str(v).replace("${WS}", ws)) for k, v in case["args"].items()]
        jobs.append((os.path.join(ws, case["launch_file"]), words, case.get("env")))

    saved = dict(os.environ)
    try:
        # warm-up (imports, package index), then the measured pass
        for path, words, env in jobs:
            os.environ.clear()
            os.environ.update(_case_env(ws, env))
            _resolve(path, words)
        start = time.perf_counter()
        for path, words, env in jobs:
            os.environ.clear()
            os.environ.update(_case_env(ws, env))
            _resolve(path, words)
        in_process = time.perf_counter() - start
    finally:
        os.environ.clear()
        os.environ.update(saved)

    per_sub = []
    for path, words, env in jobs[:samples]:
        start = time.perf_counter()
        subprocess.run([sys.executable, "-m", "orchestra", "launch", "--dump-plan", "--no-exec",
                        path, *words], env=_case_env(ws, env), capture_output=True, check=True,
                       timeout=60)
        per_sub.append(time.perf_counter() - start)
    sub = statistics.median(per_sub)
    per_case = in_process / len(jobs)
    print(f"compat cases: {len(jobs)} resolved in-process in {in_process * 1000:.0f} ms "
          f"({per_case * 1000:.2f} ms/case)")
    print(f"CLI subprocess: median {sub * 1000:.0f} ms/case over {len(per_sub)} cases "
          f"-> in-process is {sub / per_case:.0f}x cheaper per case")


def generate_tree(root: Path) -> Path:
    """A package 'big' with main.launch including level1 ... level30 in a chain."""
    pkg = root / "big"
    (pkg / "launch").mkdir(parents=True)
    (pkg / "package.xml").write_text("<package><name>big</name></package>\n")
    per_level = NODES // DEPTH
    extra = NODES - per_level * DEPTH
    for level in range(1, DEPTH + 1):
        count = per_level + (1 if level <= extra else 0)
        lines = ["<launch>", '  <arg name="rate"/>', '  <arg name="depth" default="0"/>']
        for i in range(count):
            lines.append(f'  <node name="n{level}_{i}" pkg="big" type="worker" '
                         f'args="--id {i} --rate $(arg rate)">')
            lines.append('    <remap from="in" to="d$(arg depth)/in"/>')
            for p in range(PARAMS_PER_NODE):
                lines.append(f'    <param name="p{p}" value="{p}.5"/>' if p % 2 else
                             f'    <param name="p{p}" value="$(arg rate)"/>')
            lines.append("  </node>")
        if level < DEPTH:
            lines.append(f'  <group ns="l{level}">')
            lines.append(f'    <include file="$(find big)/launch/level{level + 1}.launch">')
            lines.append('      <arg name="rate" value="$(arg rate)"/>')
            lines.append(f'      <arg name="depth" value="{level}"/>')
            lines.append("    </include>")
            lines.append("  </group>")
        lines.append("</launch>")
        (pkg / "launch" / f"level{level}.launch").write_text("\n".join(lines) + "\n")
    main = pkg / "launch" / "main.launch"
    main.write_text('<launch>\n  <arg name="rate" default="10"/>\n'
                    '  <include file="$(find big)/launch/level1.launch">\n'
                    '    <arg name="rate" value="$(arg rate)"/>\n  </include>\n</launch>\n')
    return main


def bench_synthetic() -> None:
    with tempfile.TemporaryDirectory() as tmp:
        main = generate_tree(Path(tmp))
        saved = os.environ.get("ROS_PACKAGE_PATH")
        os.environ["ROS_PACKAGE_PATH"] = tmp
        try:
            _resolve(str(main), [])  # warm-up: imports and the package index
            runs = []
            for _ in range(3):
                start = time.perf_counter()
                interp = Interpreter(LoadOptions(no_exec=True))
                interp.load_file(str(main))
                plan = interp.plan()
                runs.append(time.perf_counter() - start)
            best = min(runs)
            print(f"synthetic tree: {len(plan.nodes)} nodes, {len(plan.params)} params, "
                  f"{len(plan.files_loaded)} files ({DEPTH}-deep includes) resolved in "
                  f"{best * 1000:.0f} ms (best of 3; target < 1000 ms: "
                  f"{'OK' if best < 1.0 else 'MISSED'})")

            from orchestra.launch.substitution import resolve

            class _Scope:
                args: dict = {}
                filename = str(main)

            n = 10000
            start = time.perf_counter()
            for _ in range(n):
                resolve("$(find big)/launch/level1.launch", _Scope())
            per_find = (time.perf_counter() - start) / n
            print(f"$(find): {per_find * 1e6:.1f} us/call over {n} calls (index reused, no crawl)")
        finally:
            if saved is None:
                os.environ.pop("ROS_PACKAGE_PATH", None)
            else:
                os.environ["ROS_PACKAGE_PATH"] = saved


def main() -> int:
    import logging
    logging.basicConfig(level=logging.ERROR)  # launch-file warnings are not the point here
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--subprocess-samples", type=int, default=10)
    opts = parser.parse_args()
    if COMPAT.is_dir():
        bench_cases(opts.subprocess_samples)
    else:
        print("../shared/compat not found: skipping the compat cases")
    bench_synthetic()
    return 0


if __name__ == "__main__":
    sys.exit(main())
