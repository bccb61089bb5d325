"""Package index speed: build time and ``$(find)`` cost, cold vs warm disk cache vs in-process.

Two trees: the 118 real packages of ../shared/compat/ws and a synthetic 2,000-package tree
(40 groups x 50 packages, each package with a few sub-directories the crawl must not enter).

Figures are ratios against baselines measured in the same run, on the same machine:
  * ``catkin_pkg.packages.find_packages`` - the well-known crawler (parses every manifest),
    i.e. what a tool without an index pays per process;
  * ``python -c pass`` - interpreter start-up, the floor for any per-process figure.

Against the real ROS 1 tools (Debian's roslaunch 1.15 and rospack, /usr/bin), same trees, same
run (skipped with a message when they are missing):
  * a launch file with 1,000 ``$(find pkg)`` substitutions over the tree's packages:
    ``roslaunch --dump-params`` vs ``orchestra launch --dump-params`` (whole processes, package
    caches warm), and inside one interpreter each (the first load crawls, later ones reuse);
  * ``rospack find PKG`` vs ``orchestra pkg find PKG``, cold (no cache file) and warm.

Run:  python bench/bench_packages.py [--quick] [--repeat N] [--json out.json]
"""
from __future__ import annotations

import argparse
import contextlib
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

sys.path.insert(0, os.path.join(REPO, "bench"))
import ros1  # noqa: E402
from bench_launch import ROSLAUNCH_IN_PROCESS  # noqa: E402

FINDS = 1000

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


@contextlib.contextmanager
def package_environ(root: str, ros_home: str):
    """Point the process-wide package index at ``root`` (cache in ``ros_home``), then restore."""
    keys = ("ROS_PACKAGE_PATH", "CMAKE_PREFIX_PATH", "ROS_HOME")
    saved = {k: os.environ.get(k) for k in keys}
    os.environ.update(ROS_PACKAGE_PATH=root, ROS_HOME=ros_home)
    os.environ.pop("CMAKE_PREFIX_PATH", None)
    reset_index()
    try:
        yield
    finally:
        for k, v in saved.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v
        reset_index()


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
        with package_environ(root, cache_root):
            find_package(names[0])
            finds_t = timed(lambda: [find_package(n) for n in names], repeat)
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


def find_heavy_launch(directory: str, names: list[str]) -> str:
    """A launch file (outside the package tree) with FINDS ``$(find)`` params over ``names``."""
    path = os.path.join(directory, "finds.launch")
    with open(path, "w") as fh:
        fh.write("<launch>\n")
        for i in range(FINDS):
            name = names[i % len(names)]
            fh.write(f'  <param name="find/p{i:04d}" value="$(find {name})/launch"/>\n')
        fh.write("</launch>\n")
    return path


def bench_ros1(label: str, root: str, repeat: int, results: dict, rows: list) -> None:
    """The real roslaunch and rospack on ``root`` next to orchestra, whole processes."""
    roslaunch, rospack = ros1.tool("roslaunch"), ros1.tool("rospack")
    names = sorted(PackageIndex.build([root], cache_dir=None).packages)
    if ros1.has_modules("rospkg"):
        # only packages real ROS 1 finds (both leave metapackages out; ROS 1 also has
        # /usr/share): one unknown $(find) would make roslaunch reject the whole file
        theirs = set(ros1.run_ros1_code("import rospkg\nRESULT = rospkg.RosPack().list()", None,
                                        env=ros1.base_env(ROS_PACKAGE_PATH=root)))
        if set(names) - theirs:
            print(f"{label}: orchestra finds {len(names)} packages, real rospkg {len(theirs)} "
                  f"(ROS 1 has /usr/share too; orchestra-only: "
                  f"{', '.join(sorted(set(names) - theirs)[:5])} ...)")
        names = [name for name in names if name in theirs]
    work = tempfile.mkdtemp(prefix="orchestra-bench-finds-")
    o_home, r_home = os.path.join(work, "o_home"), os.path.join(work, "r_home")
    o_env = {**os.environ, "ROS_PACKAGE_PATH": root, "ROS_HOME": o_home}
    o_env.pop("CMAKE_PREFIX_PATH", None)
    r_env = ros1.base_env(ROS_PACKAGE_PATH=root, ROS_HOME=r_home)
    proc_repeat = max(1, repeat // 2)
    n = len(names)
    try:
        if roslaunch is None or not ros1.has_modules("roslaunch"):
            ros1.skip(f"real roslaunch $(find) on {label}", "roslaunch (ROS 1)")
        else:
            launch = find_heavy_launch(work, names)

            def run(argv, env):
                def go():
                    proc = subprocess.run(argv, env=env, cwd=work, stdout=subprocess.DEVNULL,
                                          stderr=subprocess.PIPE, text=True)
                    # real roslaunch --dump-params exits 0 when it cannot load the file
                    if proc.returncode or "Unable to load file" in proc.stderr:
                        raise RuntimeError(f"{argv[0]} failed: {proc.stderr[-300:]}")
                return go
            o_run = run(["orchestra", "launch", "--dump-params", launch], o_env)
            r_run = run([roslaunch, "--dump-params", launch], r_env)
            o_run()  # fills orchestra's package cache; roslaunch has none across processes
            o_t, r_t = timed(o_run, proc_repeat), timed(r_run, proc_repeat)
            rows.append((f"{label}: {FINDS:,} $(find) launch, --dump-params process",
                         o_t, r_t, ""))
            # inside one interpreter: the first load crawls the tree, later loads reuse it
            job = [(launch, [], ros1.base_env(ROS_PACKAGE_PATH=root))]
            res = ros1.run_ros1_code(ROSLAUNCH_IN_PROCESS,
                                     {"rounds": 3, "roscore": False,
                                      "jobs": [{"path": p, "words": w, "env": e}
                                               for p, w, e in job]})
            if res["times"][0] is None:
                print(f"real roslaunch failed on the $(find) launch: {res['errors'][0]}")
            else:
                from orchestra.launch.interpreter import Interpreter, LoadOptions

                def o_load():
                    interp = Interpreter(LoadOptions(no_exec=True))
                    interp.load_file(launch)
                    interp.plan()
                with package_environ(root, o_home):
                    start = time.perf_counter()
                    o_load()
                    o_first = time.perf_counter() - start
                    o_warm = min(timed(o_load, 1) for _ in range(3))
                rows.append(("  in-process, first load (index from disk cache / crawl)",
                             o_first, res["first"][0], ""))
                rows.append(("  in-process, later loads (index reused)", o_warm,
                             res["times"][0], ""))
        if rospack is None:
            ros1.skip(f"rospack find on {label}", "rospack")
            return
        target = names[n // 2]

        def wipe_r():
            shutil.rmtree(r_home, ignore_errors=True)

        def wipe_o():
            shutil.rmtree(o_home, ignore_errors=True)

        def pkg_find(argv, env, wipe=None):
            def go():
                if wipe:
                    wipe()
                out = subprocess.run(argv, env=env, cwd=work, check=True, capture_output=True,
                                     text=True).stdout.strip()
                assert out.endswith(target), out
            return go
        o_cmd, r_cmd = ["orchestra", "pkg", "find", target], [rospack, "find", target]
        rows.append((f"{label}: pkg find, cold (no cache)", timed(pkg_find(o_cmd, o_env, wipe_o),
                                                                   proc_repeat),
                     timed(pkg_find(r_cmd, r_env, wipe_r), proc_repeat), ""))
        pkg_find(o_cmd, o_env)()
        pkg_find(r_cmd, r_env)()
        rows.append((f"{label}: pkg find, warm cache", timed(pkg_find(o_cmd, o_env), repeat),
                     timed(pkg_find(r_cmd, r_env), repeat), ""))
    finally:
        shutil.rmtree(work, ignore_errors=True)


def print_ros1_table(rows: list) -> None:
    if not rows:
        return
    print(f"\n{'against real ROS 1':<58} {'orchestra':>10} {'ROS 1':>10} {'ratio':>7}")
    for what, ours, theirs, _ in rows:
        print(f"{what:<58} {ours * 1e3:8.1f}ms {theirs * 1e3:8.1f}ms {theirs / ours:6.1f}x")
    print("ratio = real ROS 1 time / orchestra time (higher: orchestra faster)")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=7)
    parser.add_argument("--json", help="also write the figures to this file")
    parser.add_argument("--quick", action="store_true", help="fewer repetitions")
    args = parser.parse_args()
    if args.quick:
        args.repeat = min(args.repeat, 3)
    print(ros1.load_average())

    results: dict = {}
    rows: list = []
    results["python_startup_s"] = timed(
        lambda: subprocess.run([sys.executable, "-c", "pass"], check=True), 5)
    if os.path.isdir(COMPAT_WS):
        bench_tree("compat_ws_118", COMPAT_WS, args.repeat, results)
        bench_ros1("compat ws", COMPAT_WS, args.repeat, results, rows)
    tmp = tempfile.mkdtemp(prefix="orchestra-bench-tree-")
    try:
        tree = synthetic_tree(os.path.join(tmp, "src"))
        bench_tree("synthetic_2000", tree, args.repeat, results)
        bench_ros1("2,000 pkgs", tree, args.repeat, results, rows)
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
    print_ros1_table(rows)
    print(ros1.load_average())
    results["ros1"] = [{"what": w, "orchestra_s": o, "ros1_s": r} for w, o, r, _ in rows]
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(results, fh, indent=2)


if __name__ == "__main__":
    main()
