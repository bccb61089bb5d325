"""`orchestra launch --dump-params` prints exactly what the real roslaunch prints.

Runs both on every compat case (../shared/compat) with the corpus' environment convention.
The real roslaunch comes from Debian's ROS 1 packages (installed by .ci/run when possible);
without it the module is skipped. Debian ships roslaunch 1.15, the corpus was recorded with
1.16: a case that only one of the two versions can load is not a difference of orchestra's.
"""
from __future__ import annotations

import concurrent.futures
import json
import os
import subprocess
import sys

import pytest
from conftest import COMPAT

ROSLAUNCH = "/usr/bin/roslaunch"

pytestmark = [
    pytest.mark.skipif(not os.access(ROSLAUNCH, os.X_OK), reason="real roslaunch not installed"),
    pytest.mark.skipif(not COMPAT.is_dir(), reason="../shared/compat not beside the repository"),
    pytest.mark.timeout(300),
]


def _env(case: dict, ws: str, path: str) -> dict[str, str]:
    env = {"PATH": path, "ROS_PACKAGE_PATH": ws, "ROS_DISTRO": "noetic", "LANG": "C.UTF-8"}
    env.update({k: v.replace("${WS}", ws) for k, v in (case.get("env") or {}).items()})
    return env


def _both(case: dict) -> tuple[subprocess.CompletedProcess, subprocess.CompletedProcess]:
    ws = str(COMPAT / "ws")
    launch_file = os.path.join(ws, case["launch_file"])
    args = ["{}:={}".format(k, str(v).replace("${WS}", ws)) for k, v in (case.get("args") or {}).items()]
    real = subprocess.run([ROSLAUNCH, "--dump-params", launch_file, *args],
                          env=_env(case, ws, "/usr/bin:/bin"), capture_output=True, text=True,
                          timeout=120)
    ours_path = os.pathsep.join([os.path.dirname(sys.executable), os.environ.get("PATH", "")])
    ours = subprocess.run([sys.executable, "-m", "orchestra", "launch", "--dump-params",
                           launch_file, *args], env=_env(case, ws, ours_path),
                          capture_output=True, text=True, timeout=120)
    return real, ours


def test_dump_params_text_is_identical_to_real_roslaunch_on_every_compat_case():
    cases = json.loads((COMPAT / "cases.json").read_text())
    with concurrent.futures.ThreadPoolExecutor(max(2, os.cpu_count() or 2)) as pool:
        results = list(pool.map(_both, cases))
    compared, differences = 0, []
    for case, (real, ours) in zip(cases, results, strict=False):
        # roslaunch --dump-params exits 0 even when it cannot load the file (it only prints
        # "Unable to load file" on stderr): no stdout means it did not load
        if real.returncode != 0 or not real.stdout or ours.returncode != 0:
            # version differences (1.15 vs 1.16) on what loads; the corpus pins the outcome
            continue
        compared += 1
        if real.stdout != ours.stdout:
            differences.append(case["id"])
    assert not differences, f"--dump-params differs from roslaunch on {differences}"
    # 20 cases need xacro for command= params, which Debian does not package
    assert compared >= 55, f"only {compared} cases could be compared"
