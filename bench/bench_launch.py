#!/usr/bin/env python3
"""How fast does orchestra resolve launch files? Ratios are measured in the same run.

1. The 80 real compat cases (../shared/compat) resolved in-process, against the per-case cost
   of ``orchestra launch --dump-plan --no-exec`` in a subprocess (what compare.py pays).
2. A synthetic tree generated into a temp dir: 1,000 nodes, 20,000 params, includes nested 30
   deep, every include path and many values going through ``$(find)`` and ``$(arg)``. Target:
   resolved in under 1 s.
3. ``$(find)`` cost per call once the package index is built (it must not re-crawl).
4. The real ROS 1 roslaunch (Debian's 1.15, /usr/bin) as the baseline users care about, in
   the same run: ``roslaunch --dump-params`` vs ``orchestra launch --dump-params`` per case
   (one process per case, interleaved, each case's median of 5 runs per side), roslaunch's
   ``XmlLoader`` (what ``--dump-params`` runs) over all cases inside one ROS 1 interpreter vs
   orchestra's interpreter in-process, and the synthetic tree through both. Cases real
   roslaunch cannot load here (e.g. xacro ``command=`` params without xacro installed) are
   counted and left out of both sides.
   Skipped with a message without ROS 1.
5. Start-up: ``orchestra --help`` and ``orchestra launch --dump-params`` of a one-node file
   against a bare ``python -c pass``, interleaved, medians.

Every process of both sides is pinned the same way (``taskset -c CPU``, the last CPU unless
``--cpu``). Ratios are orchestra's time / the other side's (lower: orchestra faster).

usage: python3 bench/bench_launch.py [--quick] [--subprocess-samples N] [--cpu N]
"""
from __future__ import annotations

import argparse
import json
import os
import resource
import shutil
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

sys.path.insert(0, str(REPO / "bench"))
import ros1  # noqa: E402

DEPTH = 30
NODES = 1000
PARAMS_PER_NODE = 20

# Runs inside the ROS 1 interpreter: each job is loaded once to warm up (imports), then
# ``rounds`` more times, keeping the best: XmlLoader on the launch file itself, what
# `roslaunch --dump-params` does. (`roslaunch` running a file first loads roscore.xml with
# load_config_default, whose /rosversion and /rosdistro params run `rosversion` as two
# processes per load; that is not resolving and is not compared here.) roslaunch reads
# ``name:=value`` words from sys.argv, and $(env)/$(find) from os.environ, so both are set
# per case as `roslaunch` itself would see them.
ROSLAUNCH_IN_PROCESS = """
import logging, os, sys, time
logging.disable(logging.CRITICAL)
import roslaunch.config, roslaunch.xmlloader
times, errors, first, cpu = [], [], [], []
for rnd in range(PAYLOAD["rounds"] + 1):
    for i, job in enumerate(PAYLOAD["jobs"]):
        os.environ.clear(); os.environ.update(job["env"])
        sys.argv = ["roslaunch"] + job["words"]
        t0, c0 = time.perf_counter(), time.process_time()
        try:
            cfg = roslaunch.config.ROSLaunchConfig()
            roslaunch.xmlloader.XmlLoader().load(job["path"], cfg, verbose=False)
            cfg.assign_machines()
            err = None
        except BaseException as exc:
            err = "%s: %s" % (type(exc).__name__, exc)
        dt, dc = time.perf_counter() - t0, time.process_time() - c0
        if rnd == 0:
            errors.append(err); times.append(None); cpu.append(None)
            first.append(dt if err is None else None)
        elif err is None:
            times[i] = dt if times[i] is None else min(times[i], dt)
            cpu[i] = dc if cpu[i] is None else min(cpu[i], dc)
RESULT = {"times": times, "errors": errors, "first": first, "cpu": cpu}
"""


def _case_env(ws: str, extra: dict | None) -> dict[str, str]:
    env = {"PATH": os.environ.get("PATH", "/usr/bin:/bin"), "ROS_PACKAGE_PATH": ws,
           "ROS_DISTRO": "noetic", "LANG": "C.UTF-8"}
    env.update({k: v.replace("${WS}", ws) for k, v in (extra or {}).items()})
    return env


def _resolve(path: str, words: list[str], no_exec: bool = True):
    interp = Interpreter(LoadOptions(args=load_mappings(words), no_exec=no_exec))
    interp.load_file(path)
    return interp.plan()


def _orchestra_in_process(jobs: list, rounds: int) -> tuple[list, list, list]:
    """Best-of-``rounds`` seconds per job (None when it fails), the error per job, and the
    best-of-``rounds`` CPU seconds (this process's) per job."""
    times: list = [None] * len(jobs)
    errors: list = [None] * len(jobs)
    cpu: list = [None] * len(jobs)
    saved = dict(os.environ)
    try:
        for rnd in range(rounds + 1):  # round 0 warms up imports and the package index
            for i, (path, words, env) in enumerate(jobs):
                os.environ.clear()
                os.environ.update(env)
                start, start_cpu = time.perf_counter(), time.process_time()
                try:
                    _resolve(path, words, no_exec=False)
                except Exception as exc:  # noqa: BLE001 - counted and reported, not hidden
                    errors[i] = f"{type(exc).__name__}: {exc}"
                    continue
                took, took_cpu = time.perf_counter() - start, time.process_time() - start_cpu
                if rnd:
                    times[i] = took if times[i] is None else min(times[i], took)
                    cpu[i] = took_cpu if cpu[i] is None else min(cpu[i], took_cpu)
    finally:
        os.environ.clear()
        os.environ.update(saved)
    return times, errors, cpu


def _best(times: list, more: list) -> list:
    """Per case, the smaller of two times (None: that case failed in both)."""
    return [b if a is None else a if b is None else min(a, b) for a, b in zip(times, more,
                                                                           strict=True)]


def _roslaunch_in_process(jobs: list, rounds: int) -> tuple[list, list, list]:
    """As ``_orchestra_in_process``, for roslaunch's ``XmlLoader`` in a ROS 1 interpreter."""
    payload = {"rounds": rounds,
               "jobs": [{"path": p, "words": w, "env": ros1.base_env(**e)} for p, w, e in jobs]}
    result = ros1.run_ros1_code(ROSLAUNCH_IN_PROCESS, payload)
    return result["times"], result["errors"], result["cpu"]


PIN: list[str] = []


def orchestra_script() -> str:
    """The ``orchestra`` console script pip installed beside this interpreter (what a user's
    PATH finds after ``pip install``), not a version manager's shim: pyenv's bash shims add
    ~30 ms per process that are neither orchestra's nor roslaunch's (/usr/bin/roslaunch is
    run directly)."""
    beside = os.path.join(os.path.dirname(sys.executable), "orchestra")
    return beside if os.access(beside, os.X_OK) else (shutil.which("orchestra") or "orchestra")


def _orchestra_env(env: dict) -> dict:
    """``env`` for an orchestra process: this checkout's code first on ``sys.path`` (the
    editable install may point at another checkout)."""
    return {**env, "PYTHONPATH": str(REPO)}


def _without_site_hooks(env: dict) -> tuple[list[str], dict]:
    """argv prefix and ``env`` of orchestra run by ``python -S`` with site-packages on
    PYTHONPATH: the same code and dependencies without this interpreter's ``.pth`` start-up
    hooks (this machine's certificate hook, which imports certifi and importlib.resources) that every
    ``python`` here runs first and Debian's python3, which runs roslaunch, does not: about
    what a plain ``pip install`` in a virtualenv gives (which keeps site's own ~2 ms)."""
    import site

    path = os.pathsep.join([str(REPO), *site.getsitepackages()])
    return [sys.executable, "-S", "-m", "orchestra"], {**env, "PYTHONPATH": path}


def compile_bytecode() -> None:
    """Byte-compile orchestra's modules, as ``pip install`` leaves them: with
    PYTHONDONTWRITEBYTECODE set (as on this machine) or a checkout that changed since it last
    ran, every process would otherwise compile the changed modules from source (~30 ms),
    which is no user's start-up. (Debian's roslaunch is byte-compiled at install too.)"""
    import compileall

    compileall.compile_dir(str(REPO / "orchestra"), quiet=2)


def _pinned(argv: list[str]) -> list[str]:
    """``argv`` under the same ``taskset`` as every other measured process."""
    return [*PIN, *argv]


def _subprocess_time(argv: list[str], env: dict) -> tuple[float, bool]:
    """Seconds and success of one run; success also needs no "Unable to load file" on stderr,
    because real ``roslaunch --dump-params`` exits 0 when it cannot load the file."""
    took, _, ok = _subprocess_times(argv, env)
    return took, ok


def _children_cpu() -> float:
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def _subprocess_times(argv: list[str], env: dict) -> tuple[float, float, bool]:
    """Wall seconds, CPU seconds (user + system, of the process and anything it waited for)
    and success of one run (see ``_subprocess_time``). CPU time is what the other helpers'
    load on a shared machine disturbs least."""
    cpu = _children_cpu()
    start = time.perf_counter()
    proc = subprocess.run(argv, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                          timeout=120)
    took = time.perf_counter() - start
    return took, _children_cpu() - cpu, \
        proc.returncode == 0 and b"Unable to load file" not in proc.stderr


def bench_cases(samples: int, rounds: int, repeats: int, rows: list) -> None:
    cases = json.loads((COMPAT / "cases.json").read_text())
    ws = str(COMPAT / "ws")
    jobs = []
    for case in cases:
        words = ["{}:={}".format(k, str(v).replace("${WS}", ws)) for k, v in case["args"].items()]
        jobs.append((os.path.join(ws, case["launch_file"]), words, _case_env(ws, case.get("env"))))

    # orchestra alone, as before: the compare.py contract (--no-exec), in-process vs its CLI
    saved = dict(os.environ)
    try:
        for _ in range(2):  # warm-up pass, then the measured pass
            start = time.perf_counter()
            for path, words, env in jobs:
                os.environ.clear()
                os.environ.update(env)
                _resolve(path, words)
            in_process = time.perf_counter() - start
    finally:
        os.environ.clear()
        os.environ.update(saved)
    per_sub = [_subprocess_time([sys.executable, "-m", "orchestra", "launch", "--dump-plan",
                                 "--no-exec", path, *words], _orchestra_env(env))[0]
               for path, words, env in jobs[:samples]]
    sub = statistics.median(per_sub)
    per_case = in_process / len(jobs)
    print(f"compat cases (--no-exec): {len(jobs)} resolved in-process in "
          f"{in_process * 1000:.0f} ms ({per_case * 1000:.2f} ms/case)")
    print(f"orchestra CLI subprocess: median {sub * 1000:.0f} ms/case over {len(per_sub)} cases "
          f"-> in-process is {sub / per_case:.0f}x cheaper per case")

    roslaunch = ros1.tool("roslaunch")
    if roslaunch is None or not ros1.has_modules("roslaunch"):
        ros1.skip("the real roslaunch on the compat cases", "roslaunch (ROS 1)")
        return
    # the same work on both sides: command= params are executed, as roslaunch does; rounds
    # alternate between the two sides (interleaved), each case keeps its best
    o_times, o_errors, o_cpu = _orchestra_in_process(jobs, 1)
    r_times, r_errors, r_cpu = _roslaunch_in_process(jobs, 1)
    for _ in range(rounds - 1):
        o_more, _, o_more_cpu = _orchestra_in_process(jobs, 1)
        r_more, _, r_more_cpu = _roslaunch_in_process(jobs, 1)
        o_times, o_cpu = _best(o_times, o_more), _best(o_cpu, o_more_cpu)
        r_times, r_cpu = _best(r_times, r_more), _best(r_cpu, r_more_cpu)
    both = [i for i in range(len(jobs)) if o_times[i] is not None and r_times[i] is not None]
    r_fail = [i for i in range(len(jobs)) if r_times[i] is None]
    o_fail = [i for i in range(len(jobs)) if o_times[i] is None]
    example = " ".join((r_errors[r_fail[0]] or "").split())[-160:] if r_fail else "-"
    print(f"real roslaunch cannot load {len(r_fail)} of {len(jobs)} cases here "
          f"(skipped on both sides), e.g. {example}")
    only_o = sorted(set(o_fail) - set(r_fail))
    if only_o:
        print(f"orchestra failed {len(only_o)} cases real roslaunch loads: "
              + "; ".join(f"{cases[i]['id']}: {o_errors[i][:100]}" for i in only_o[:3]))
    o_sum = sum(o_times[i] for i in both)
    r_sum = sum(r_times[i] for i in both)
    rows.append((f"{len(both)} cases in-process vs XmlLoader, best of {rounds} interleaved",
                 f"{o_sum * 1e3:.0f} ms", f"{r_sum * 1e3:.0f} ms", o_sum / r_sum, "<= 0.2x"))
    # CPU time of the same loops: what other processes on a busy machine take away from the
    # wall-clock sums above does not count here
    o_cpu_sum = sum(o_cpu[i] for i in both)
    r_cpu_sum = sum(r_cpu[i] for i in both)
    rows.append(("  same, CPU time (process_time) of each side", f"{o_cpu_sum * 1e3:.0f} ms",
                 f"{r_cpu_sum * 1e3:.0f} ms", o_cpu_sum / r_cpu_sum, ""))
    o_med = statistics.median(o_times[i] for i in both)
    r_med = statistics.median(r_times[i] for i in both)
    rows.append(("  per case, median", f"{o_med * 1e3:.2f} ms", f"{r_med * 1e3:.2f} ms",
                 o_med / r_med, ""))

    sub_jobs = both[:samples]
    o_sub, r_sub, bare_sub, o_cpu, r_cpu = [], [], [], [], []
    for i in sub_jobs:  # interleaved: each case through orchestra, roslaunch and python -S,
        path, words, env = jobs[i]        # `repeats` times; each side keeps its median
        bare, bare_env = _without_site_hooks(env)
        runs: dict[str, list[tuple[float, float]]] = {"o": [], "r": [], "b": []}
        for _ in range(repeats):
            for side, argv, side_env in (
                    ("o", [orchestra_script(), "launch", "--dump-params", path, *words],
                     _orchestra_env(env)),
                    ("r", [roslaunch, "--dump-params", path, *words], ros1.base_env(**env)),
                    ("b", [*bare, "launch", "--dump-params", path, *words], bare_env)):
                t, cpu, ok = _subprocess_times(_pinned(argv), side_env)
                if ok:
                    runs[side].append((t, cpu))
        if not (runs["o"] and runs["r"]):
            continue
        o_sub.append(statistics.median(t for t, _ in runs["o"]))
        o_cpu.append(statistics.median(c for _, c in runs["o"]))
        r_sub.append(statistics.median(t for t, _ in runs["r"]))
        r_cpu.append(statistics.median(c for _, c in runs["r"]))
        if runs["b"]:
            bare_sub.append(statistics.median(t for t, _ in runs["b"]))
    each = f"median of {repeats} interleaved runs per case"
    rows.append((f"--dump-params, one process per case, median of {len(o_sub)} cases",
                 f"{statistics.median(o_sub) * 1e3:.0f} ms",
                 f"{statistics.median(r_sub) * 1e3:.0f} ms",
                 statistics.median(o_sub) / statistics.median(r_sub), ""))
    rows.append((f"  whole corpus, sum over the {len(o_sub)} cases ({each})", f"{sum(o_sub):.1f} s",
                 f"{sum(r_sub):.1f} s", sum(o_sub) / sum(r_sub), "<= 0.2x"))
    rows.append(("  same, CPU time (user + system) of the processes", f"{sum(o_cpu):.1f} s",
                 f"{sum(r_cpu):.1f} s", sum(o_cpu) / sum(r_cpu), ""))
    rows.append(("  same, orchestra without this python's .pth hooks (python -S)",
                 f"{sum(bare_sub):.1f} s", f"{sum(r_sub):.1f} s", sum(bare_sub) / sum(r_sub), ""))


ONE_NODE = """<launch>
  <node name="talker" pkg="rospy_tutorials" type="talker.py">
    <param name="rate" value="10"/>
  </node>
</launch>
"""


def bench_startup(samples: int, rows: list) -> None:
    """``orchestra --help`` and a one-node ``--dump-params`` against ``python -c pass``."""
    with tempfile.TemporaryDirectory() as tmp:
        one = Path(tmp) / "one_node.launch"
        one.write_text(ONE_NODE)
        env = _orchestra_env(dict(os.environ))
        runs = {"python -c pass": [sys.executable, "-c", "pass"],
                "python -S -c pass": [sys.executable, "-S", "-c", "pass"],
                "orchestra --help": [orchestra_script(), "--help"],
                "orchestra launch --dump-params one_node.launch":
                    [orchestra_script(), "launch", "--dump-params", str(one)]}
        times: dict[str, list[float]] = {what: [] for what in runs}
        cpus: dict[str, list[float]] = {what: [] for what in runs}
        for _ in range(samples):  # interleaved
            for what, argv in runs.items():
                took, cpu, ok = _subprocess_times(_pinned(argv), env)
                if not ok:
                    print(f"start-up: {what} failed")
                    return
                times[what].append(took)
                cpus[what].append(cpu)
    base = statistics.median(times["python -c pass"])
    print(f"start-up: python -c pass {base * 1e3:.0f} ms, of which this interpreter's site "
          "start-up (its .pth hooks, e.g. a certificate hook) "
          f"{(base - statistics.median(times['python -S -c pass'])) * 1e3:.0f} ms")
    base_cpu = statistics.median(cpus["python -c pass"])
    for what in list(runs)[2:]:
        ours = statistics.median(times[what])
        rows.append((f"{what} (median of {samples})", f"{ours * 1e3:.0f} ms",
                     f"{base * 1e3:.0f} ms", ours / base, "<= 2x"))
        ours_cpu = statistics.median(cpus[what])
        rows.append(("  same, CPU time (user + system)", f"{ours_cpu * 1e3:.0f} ms",
                     f"{base_cpu * 1e3:.0f} ms", ours_cpu / base_cpu, ""))


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


def bench_synthetic(runs: int, rows: list) -> None:
    with tempfile.TemporaryDirectory() as tmp:
        main = generate_tree(Path(tmp))
        saved = os.environ.get("ROS_PACKAGE_PATH")
        os.environ["ROS_PACKAGE_PATH"] = tmp
        try:
            _resolve(str(main), [])  # warm-up: imports and the package index
            times = []
            for _ in range(max(3, runs)):
                start = time.perf_counter()
                interp = Interpreter(LoadOptions(no_exec=True))
                interp.load_file(str(main))
                plan = interp.plan()
                times.append(time.perf_counter() - start)
            best = min(times)
            print(f"synthetic tree: {len(plan.nodes)} nodes, {len(plan.params)} params, "
                  f"{len(plan.files_loaded)} files ({DEPTH}-deep includes) resolved in "
                  f"{best * 1000:.0f} ms (best of {len(times)}; target < 1000 ms: "
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

        roslaunch = ros1.tool("roslaunch")
        if roslaunch is None or not ros1.has_modules("roslaunch"):
            ros1.skip("the real roslaunch on the synthetic tree", "roslaunch (ROS 1)")
            return
        env = _case_env(tmp, None)
        r_times, r_errors, _ = _roslaunch_in_process([(str(main), [], env)], runs)
        if r_times[0] is None:
            print(f"real roslaunch failed on the synthetic tree: {r_errors[0]}")
            return
        rows.append((f"synthetic {NODES} nodes/{NODES * PARAMS_PER_NODE} params/{DEPTH}-deep, "
                     "in-process vs XmlLoader", f"{best * 1e3:.0f} ms",
                     f"{r_times[0] * 1e3:.0f} ms", best / r_times[0], "<= 0.2x"))
        o_ts, r_ts = [], []
        for _ in range(5):  # interleaved
            o_t, o_ok = _subprocess_time(_pinned([orchestra_script(), "launch", "--dump-params",
                                                  str(main)]), _orchestra_env(env))
            r_t, r_ok = _subprocess_time(_pinned([roslaunch, "--dump-params", str(main)]),
                                         ros1.base_env(**env))
            if not (o_ok and r_ok):
                print(f"--dump-params on the synthetic tree failed: orchestra ok={o_ok}, "
                      f"roslaunch ok={r_ok}")
                return
            o_ts.append(o_t)
            r_ts.append(r_t)
        o_t, r_t = statistics.median(o_ts), statistics.median(r_ts)
        rows.append(("  same tree, --dump-params process, median of 5", f"{o_t * 1e3:.0f} ms",
                     f"{r_t * 1e3:.0f} ms", o_t / r_t, "<= 0.25x"))


def print_table(rows: list) -> None:
    if not rows:
        return
    print()
    print(f"{'what':<62} {'orchestra':>11} {'baseline':>11} {'ratio':>7}  target")
    for what, ours, theirs, ratio, target in rows:
        print(f"{what:<62} {ours:>11} {theirs:>11} {ratio:>6.2f}x  {target}")
    print("ratio = orchestra time / baseline time (real roslaunch, or python -c pass for the "
          "start-up rows; lower: orchestra faster)")


def main() -> int:
    import logging
    logging.basicConfig(level=logging.ERROR)  # launch-file warnings are not the point here
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--subprocess-samples", type=int, default=None,
                        help="cases run as subprocesses (default: all 80; 10 with --quick)")
    parser.add_argument("--quick", action="store_true", help="fewer samples and rounds")
    parser.add_argument("--cpu", type=int, default=None,
                        help="pin every measured process to this CPU (default: the last one; "
                             "-1: no pinning)")
    opts = parser.parse_args()
    cpu = (os.cpu_count() or 1) - 1 if opts.cpu is None else opts.cpu
    if cpu >= 0 and shutil.which("taskset"):
        PIN[:] = ["taskset", "-c", str(cpu)]
    samples = opts.subprocess_samples or (10 if opts.quick else 80)
    rounds = 1 if opts.quick else 3
    print(ros1.load_average())
    compile_bytecode()
    rows: list = []
    bench_startup(7 if opts.quick else 15, rows)
    if COMPAT.is_dir():
        bench_cases(samples, rounds, 3 if opts.quick else 5, rows)
    else:
        print("../shared/compat not found: skipping the compat cases")
    bench_synthetic(1 if opts.quick else 2, rows)
    print_table(rows)
    print(ros1.load_average())
    return 0


if __name__ == "__main__":
    sys.exit(main())
