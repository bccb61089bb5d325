"""Where the real ROS 1 tools are, and how the bench scripts run them.

The real ROS 1 (Debian's ros-* packages: roslaunch 1.15, rosmaster, rospy, rospack) lives
under ``/usr/bin`` and ``/usr/bin/python3``, not in the interpreter that runs orchestra. Each
bench script uses this module to find it and to skip its ROS 1 rows with one clear line
when it is missing, so every script stays runnable on a machine without ROS.

Code that must run inside the ROS 1 interpreter is passed to it as a string (``run_ros1_code``)
because this module is imported by the orchestra-side interpreter and must not import rospy.
"""
from __future__ import annotations

import atexit
import functools
import json
import os
import shutil
import signal
import subprocess
import tempfile

import psutil

ROS1_PYTHON = os.environ.get("ORCHESTRA_BENCH_ROS1_PYTHON", "/usr/bin/python3")
ROS1_BIN = os.environ.get("ORCHESTRA_BENCH_ROS1_BIN", "/usr/bin")


def tool(name: str) -> str | None:
    """Absolute path of the real ROS 1 executable ``name`` (roslaunch, rosmaster, rospack)."""
    path = os.path.join(ROS1_BIN, name)
    return path if os.access(path, os.X_OK) else None


@functools.cache
def has_modules(*modules: str) -> bool:
    """True when the ROS 1 interpreter imports every module (e.g. rospy, roslaunch)."""
    if not os.access(ROS1_PYTHON, os.X_OK):
        return False
    code = "; ".join(f"import {m}" for m in modules)
    try:
        proc = subprocess.run([ROS1_PYTHON, "-c", code], env=base_env(), capture_output=True,
                              timeout=60)
    except (OSError, subprocess.TimeoutExpired):
        return False
    return proc.returncode == 0


def base_env(**extra: str) -> dict[str, str]:
    """A minimal environment for a ROS 1 process: no pyenv/venv variables leak into it.

    ROS_HOME points to a private directory so real roslaunch's logs and rospack's cache do
    not mix with the user's.
    """
    env = {"PATH": "/usr/bin:/bin", "LANG": "C.UTF-8", "HOME": os.environ.get("HOME", "/tmp"),
           "ROS_DISTRO": "noetic", "ROS_HOME": _ros_home()}
    env.update(extra)
    return env


@functools.cache
def _ros_home() -> str:
    """One private ROS_HOME per bench run, removed when the run ends."""
    path = tempfile.mkdtemp(prefix="orchestra-bench-ros1-home-")
    atexit.register(shutil.rmtree, path, ignore_errors=True)
    return path


def run_ros1_code(code: str, payload: object, env: dict[str, str] | None = None,
                  timeout: float = 600) -> object:
    """Run ``code`` in the ROS 1 interpreter with ``payload`` (JSON) and return its result.

    The code reads ``PAYLOAD`` and must assign ``RESULT``; both travel through temp files so
    whatever roslaunch prints on stdout cannot corrupt them.
    """
    with tempfile.TemporaryDirectory() as tmp:
        inp, out = os.path.join(tmp, "in.json"), os.path.join(tmp, "out.json")
        with open(inp, "w") as fh:
            json.dump(payload, fh)
        wrapper = (f"import json\nPAYLOAD = json.load(open({inp!r}))\n{code}\n"
                   f"json.dump(RESULT, open({out!r}, 'w'))\n")
        proc = subprocess.run([ROS1_PYTHON, "-c", wrapper], env=env or base_env(),
                              stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
                              timeout=timeout)
        if proc.returncode != 0:
            raise RuntimeError(f"ROS 1 helper failed: {proc.stderr.strip()[-800:]}")
        with open(out) as fh:
            return json.load(fh)


def skip(what: str, missing: str) -> None:
    """One line saying which ROS 1 comparison is skipped and why."""
    print(f"[ROS 1] skipping {what}: {missing} not found")


def load_average() -> str:
    one, five, fifteen = os.getloadavg()
    return f"load average {one:.2f} {five:.2f} {fifteen:.2f} on {os.cpu_count()} cores"


def kill_tree(pid: int, sig: int = signal.SIGKILL) -> None:
    """Send ``sig`` to ``pid`` and every descendant (processes this bench started)."""
    try:
        parent = psutil.Process(pid)
        procs = parent.children(recursive=True) + [parent]
    except psutil.NoSuchProcess:
        return
    for proc in procs:
        try:
            proc.send_signal(sig)
        except psutil.NoSuchProcess:
            pass
