"""orchestra resolves the shared compat corpus exactly as the real roslaunch 1.16 does.

Each case, roslaunch fixture and smoke file of ../shared/compat is one test, run in-process
through the interpreter with compare.py's own normalisation and comparison (imported from
../shared, not copied), under compare.py's environment convention: only PATH,
ROS_PACKAGE_PATH, ROS_DISTRO and the case's env are set. A few cases also go through the real
CLI in a subprocess, as compare.py does.
"""
from __future__ import annotations

import importlib.util
import json
import os
import subprocess
import sys
import warnings

import pytest
from conftest import COMPAT

from orchestra.errors import OrchestraError
from orchestra.launch.interpreter import Interpreter, LoadOptions, binary_to_json
from orchestra.names import load_mappings


def _compare_module():
    path = COMPAT / "compare.py"
    if not path.is_file():
        return None
    spec = importlib.util.spec_from_file_location("shared_compat_compare", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


COMPARE = _compare_module()


def _jobs(which: str) -> list:
    if COMPARE is None:
        return []
    # the shared compare.py reads its JSON with json.load(open(...)) and leaves the closing to
    # the garbage collector; it is shared material, not ours to edit
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ResourceWarning)
        return COMPARE.jobs_for(which)


def _ids(jobs: list) -> list[str]:
    return [job[0] for job in jobs]


def _set_environment(monkeypatch, ws: str, env: dict | None) -> None:
    """compare.py's convention: nothing but PATH, ROS_PACKAGE_PATH, ROS_DISTRO + case env."""
    path = os.environ.get("PATH", "/usr/bin:/bin")
    for key in list(os.environ):
        monkeypatch.delenv(key)
    monkeypatch.setenv("PATH", path)
    monkeypatch.setenv("ROS_PACKAGE_PATH", ws)
    monkeypatch.setenv("ROS_DISTRO", "noetic")
    monkeypatch.setenv("LANG", "C.UTF-8")
    for key, value in (env or {}).items():
        monkeypatch.setenv(key, value.replace("${WS}", ws))


def _resolve_in_process(ws: str, launch_file: str, args: dict | None):
    words = ["{}:={}".format(k, str(v).replace("${WS}", ws)) for k, v in (args or {}).items()]
    interp = Interpreter(LoadOptions(args=load_mappings(words), no_exec=True))
    interp.load_file(launch_file)
    # round-trip through JSON exactly like the CLI output compare.py reads
    return json.loads(json.dumps(interp.plan().to_json(), default=binary_to_json))


def _check(monkeypatch, job) -> None:
    _, ws, launch_file, args, env, expected = job
    _set_environment(monkeypatch, ws, env)
    if not expected.get("ok", True):
        with pytest.raises(OrchestraError) as info:
            _resolve_in_process(ws, launch_file, args)
        assert str(info.value), "a rejection must carry a message"
        return
    got = _resolve_in_process(ws, launch_file, args)
    if expected.get("load_only"):
        return
    diff = COMPARE.first_difference(expected, COMPARE.normalize(got, ws))
    assert diff is None, diff


CASES = _jobs("cases")
FIXTURES = _jobs("fixtures")
SMOKE = _jobs("smoke")


@pytest.mark.skipif(COMPARE is None, reason="../shared/compat is not beside the repository")
@pytest.mark.parametrize("job", CASES, ids=_ids(CASES))
def test_real_launch_file_resolves_like_roslaunch(monkeypatch, job):
    _check(monkeypatch, job)


@pytest.mark.skipif(COMPARE is None, reason="../shared/compat is not beside the repository")
@pytest.mark.parametrize("job", FIXTURES, ids=_ids(FIXTURES))
def test_roslaunch_fixture_is_accepted_or_rejected_like_roslaunch(monkeypatch, job):
    _check(monkeypatch, job)


@pytest.mark.skipif(COMPARE is None, reason="../shared/compat is not beside the repository")
@pytest.mark.parametrize("job", SMOKE, ids=_ids(SMOKE))
def test_smoke_file_loads_or_is_rejected_like_roslaunch(monkeypatch, job):
    _check(monkeypatch, job)


def _cli_job(prefix: str):
    for job in CASES + FIXTURES:
        if job[0].startswith(prefix):
            return job
    pytest.skip(f"{prefix} not in the corpus")


@pytest.mark.timeout(120)
@pytest.mark.parametrize("name", ["case turtle_tf__turtle_tf_demo",
                                  "fixture test-params-valid.xml",
                                  "fixture test-node-invalid-name-2.xml"])
def test_cli_dump_plan_matches_roslaunch_through_a_subprocess(compat_dir, name):
    job = _cli_job(name)
    ok, message = COMPARE.check_case(f"{sys.executable} -m orchestra", *job[1:])
    assert ok, message


@pytest.mark.timeout(60)
def test_cli_rejection_is_one_located_line_without_traceback(compat_dir):
    ws = str(compat_dir / "fixtures" / "ws")
    path = os.path.join(ws, "roslaunch", "test", "xml", "test-node-invalid-respawn.xml")
    env = {"PATH": os.environ["PATH"], "ROS_PACKAGE_PATH": ws, "ROS_DISTRO": "noetic"}
    proc = subprocess.run([sys.executable, "-m", "orchestra", "launch", "--dump-plan",
                           "--no-exec", path], env=env, capture_output=True, text=True,
                          timeout=60)
    assert proc.returncode == 2
    assert "Traceback" not in proc.stderr
    assert f"{path}:" in proc.stderr and "respawn" in proc.stderr
