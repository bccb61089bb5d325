"""Package index speed: build time and ``$(find)`` cost, cold vs warm disk cache vs in-process.

Two trees: the 118 real packages of ../shared/compat/ws and a synthetic 2,000-package tree
(40 groups x 50 packages, each package with a few sub-directories the crawl must not enter).

Figures are ratios against baselines measured in the same run, on the same machine:
  * ``catkin_pkg.packages.find_packages`` - the well-known crawler (parses every manifest),
    i.e. what a tool without an index pays per process;
  * ``python -c pass`` - interpreter start-up, the floor for any per-process figure.

Run:  python bench/bench_packages.py [--repeat N] [--json out.json]
"""
from __future__ import annotations

import argparse
import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, REPO)

from orchestra.packages.index import PackageIndex, find_package, reset_index  # noqa: E402

COMPAT_WS = os.path.join(os.path.dirname(REPO), "shared", "compat", "ws")
OLD = time.time() - 3600

MANIFEST = """<?xml version="1.0"?>
<package format="2">
  <name>{name}</name>
  <version>1.0.0</version>
  <description>synthetic package {name}</description>
  <maintainer email="bench@example.com">Bench</maintainer>
  <license>BSD</license>
  <buildtool_depend>catkin</buildtool_depend>
  <depend>roscpp</depend>
  <depend>std_msgs</depend>
</package>
"""


def synthetic_tree(root: str, groups: int = 40, per_group: int = 50) -> str:
    for g in range(groups):
        for p in range(per_group):
            pkg = os.path.join(root, f"group_{g:02d}", f"pkg_{g:02d}_{p:02d}")
            for sub in ("launch", "config", os.path.join("src", "module")):
                os.makedirs(os.path.join(pkg, sub))
            with open(os.path.join(pkg, "package.xml"), "w") as fh:
                fh.write(MANIFEST.format(name=os.path.basename(pkg)))
            with open(os.path.join(pkg, "launch", "x.launch"), "w") as fh:
                fh.write("<launch/>\n")
    # a tree nobody touched in the last hour: the cache may trust every mtime (a freshly
    # written directory is re-listed on purpose, see crawl.RACY_WINDOW_NS)
    for directory, dirs, files in os.walk(root):
        for entry in dirs + files:
            os.utime(os.path.join(directory, entry), (OLD, OLD))
    os.utime(root, (OLD, OLD))
    return root


def timed(fn, repeat: int) -> float:
    """Median seconds of ``repeat`` calls."""
    samples = []
    for _ in range(repeat):
        start = time.perf_counter()
        fn()
        samples.append(time.perf_counter() - start)
    return statistics.median(samples)


def bench_tree(label: str, root: str, repeat: int, results: dict) -> None:
    from catkin_pkg.packages import find_packages

    some_names = None
    cache_root = tempfile.mkdtemp(prefix="orchestra-bench-cache-")
    try:
        baseline = timed(lambda: find_packages(root), max(1, repeat // 2))

        def cold():
            shutil.rmtree(cache_root, ignore_errors=True)
            return PackageIndex.build([root], cache_dir=cache_root)

        cold_t = timed(cold, repeat)
        index = PackageIndex.build([root], cache_dir=cache_root)  # make sure the cache is full
        warm = PackageIndex.build([root], cache_dir=cache_root)
        assert warm.listed == 0, "warm build still listed directories"
        warm_t = timed(lambda: PackageIndex.build([root], cache_dir=cache_root), repeat)
        nocache_t = timed(lambda: PackageIndex.build([root], cache_dir=None), repeat)
        some_names = sorted(index.packages)
        names = [some_names[i % len(some_names)] for i in range(1000)]
        # through the public entry point the launch interpreter uses, process index built once
        saved = {k: os.environ.get(k) for k in ("ROS_PACKAGE_PATH", "CMAKE_PREFIX_PATH", "ROS_HOME")}
        os.environ.update(ROS_PACKAGE_PATH=root, ROS_HOME=cache_root)
        os.environ.pop("CMAKE_PREFIX_PATH", None)
        reset_index()
        try:
            find_package(names[0])
            finds_t = timed(lambda: [find_package(n) for n in names], repeat)
        finally:
            for k, v in saved.items():
                if v is None:
                    os.environ.pop(k, None)
                else:
                    os.environ[k] = v
            reset_index()
        results[label] = {
            "packages": len(index.packages),
            "catkin_pkg_find_packages_s": baseline,
            "cold_build_s": cold_t, "no_cache_build_s": nocache_t, "warm_build_s": warm_t,
            "in_process_1000_finds_s": finds_t,
            "cold_vs_catkin_pkg": baseline / cold_t, "warm_vs_catkin_pkg": baseline / warm_t,
            "warm_vs_cold": cold_t / warm_t,
            "finds_1000_vs_catkin_pkg": baseline / finds_t,
        }
        # a whole process: interpreter + import + index + one lookup
        env = {**os.environ, "ROS_PACKAGE_PATH": root, "ROS_HOME": cache_root}
        cmd = [sys.executable, "-m", "orchestra", "pkg", "find", some_names[len(some_names) // 2]]

        def run_cli():
            subprocess.run(cmd, env=env, cwd=tempfile.gettempdir(), check=True,
                           stdout=subprocess.DEVNULL)

        def run_cli_cold():
            shutil.rmtree(cache_root, ignore_errors=True)
            run_cli()

        proc_repeat = max(3, repeat // 2)
        results[label]["process_cold_s"] = timed(run_cli_cold, proc_repeat)
        run_cli()
        results[label]["process_warm_s"] = timed(run_cli, proc_repeat)
    finally:
        shutil.rmtree(cache_root, ignore_errors=True)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=7)
    parser.add_argument("--json", help="also write the figures to this file")
    args = parser.parse_args()

    results: dict = {}
    results["python_startup_s"] = timed(
        lambda: subprocess.run([sys.executable, "-c", "pass"], check=True), 5)
    if os.path.isdir(COMPAT_WS):
        bench_tree("compat_ws_118", COMPAT_WS, args.repeat, results)
    tmp = tempfile.mkdtemp(prefix="orchestra-bench-tree-")
    try:
        bench_tree("synthetic_2000", synthetic_tree(os.path.join(tmp, "src")), args.repeat, results)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)

    print(f"python start-up (baseline floor): {results['python_startup_s'] * 1e3:.1f} ms")
    for label, r in results.items():
        if not isinstance(r, dict):
            continue
        print(f"\n{label}: {r['packages']} packages")
        print(f"  catkin_pkg find_packages (baseline) {r['catkin_pkg_find_packages_s'] * 1e3:9.2f} ms")
        print(f"  index build, cold (no cache file)   {r['cold_build_s'] * 1e3:9.2f} ms"
              f"   x{r['cold_vs_catkin_pkg']:.1f} faster than baseline")
        print(f"  index build, warm disk cache        {r['warm_build_s'] * 1e3:9.2f} ms"
              f"   x{r['warm_vs_catkin_pkg']:.1f} faster than baseline, x{r['warm_vs_cold']:.1f} vs cold")
        print(f"  index build, cache disabled         {r['no_cache_build_s'] * 1e3:9.2f} ms")
        print(f"  1000 $(find) in-process             {r['in_process_1000_finds_s'] * 1e3:9.3f} ms"
              f"   ({r['in_process_1000_finds_s'] * 1e6 / 1000:.2f} us per find)")
        print(f"  `orchestra pkg find` process, cold  {r['process_cold_s'] * 1e3:9.1f} ms")
        print(f"  `orchestra pkg find` process, warm  {r['process_warm_s'] * 1e3:9.1f} ms")
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(results, fh, indent=2)


if __name__ == "__main__":
    main()
