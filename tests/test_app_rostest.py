"""``orchestra test`` (rostest): verdicts, the combined JUnit file, exit codes, bad input,
the bundled rostest helpers, and the same test programs under Debian's real rostest.

The test programs live in tests/app_files/rostest_pkg (a package, so real rostest finds
them too); they need only the standard library (or orchestra.node for the talker).
"""
from __future__ import annotations

import os
import shutil
import signal
import subprocess
import sys
from pathlib import Path

import psutil
import pytest
from lxml import etree

from orchestra.app.junit import ERROR, FAILURE, PASSED, SKIPPED, ResultsError, parse_results

HERE = Path(__file__).resolve().parent
PKG_ROOT = HERE / "app_files"
TESTS = PKG_ROOT / "rostest_pkg" / "test"
REPO = HERE.parent

pytestmark = pytest.mark.timeout(180)


def env_for(tmp_path: Path) -> dict[str, str]:
    env = {k: v for k, v in os.environ.items()
           if k not in ("ROS_PACKAGE_PATH", "CMAKE_PREFIX_PATH", "ROS_NAMESPACE", "DISPLAY",
                        "ROS_TEST_RESULTS_DIR", "ROS_LOG_DIR")}
    env.update(ROS_PACKAGE_PATH=str(PKG_ROOT), ROS_HOME=str(tmp_path / "ros_home"),
               PYTHONUNBUFFERED="1")
    return env


def orchestra_test(tmp_path: Path, *words: str) -> tuple[subprocess.CompletedProcess, Path]:
    out = tmp_path / "junit.xml"
    proc = subprocess.run([sys.executable, "-m", "orchestra", "test", *words,
                           "--junit-xml", str(out), "--results-dir", str(tmp_path / "results")],
                          env=env_for(tmp_path), cwd=tmp_path, capture_output=True, text=True,
                          timeout=150, stdin=subprocess.DEVNULL)
    return proc, out


def verdicts(junit: Path) -> dict[str, str]:
    """test (suite) name -> worst verdict of its cases, from the combined file."""
    root = etree.parse(str(junit)).getroot()
    found = {}
    for suite in root.iter("testsuite"):
        kinds = {child.tag for case in suite.iter("testcase") for child in case}
        found[suite.get("name")] = ("error" if "error" in kinds else
                                    "failure" if "failure" in kinds else "passed")
    return found


def left_running(tmp_path: Path) -> list[str]:
    """Processes whose working directory is this test's ROS_HOME (every node's and test's)."""
    home = str(tmp_path / "ros_home")
    found = []
    for proc in psutil.process_iter(["pid", "cwd", "cmdline"]):
        cwd = proc.info.get("cwd") or ""
        if cwd.startswith(home):
            found.append(f"{proc.info['pid']} {' '.join(proc.info.get('cmdline') or [])}")
    return found


def test_pass_fail_and_time_limit_give_three_cases_exit_1_and_nothing_left(tmp_path):
    proc, junit = orchestra_test(tmp_path, str(TESTS / "verdicts.test"))
    assert proc.returncode == 1, proc.stdout + proc.stderr
    assert verdicts(junit) == {"passes": "passed", "fails": "failure", "hangs": "failure"}
    root = etree.parse(str(junit)).getroot()
    assert (root.get("tests"), root.get("failures"), root.get("errors")) == ("3", "2", "0")
    assert "time-limit of 3 s exceeded" in proc.stdout
    assert " * RESULT: FAIL" in proc.stdout and " * FAILURES: 2" in proc.stdout
    assert left_running(tmp_path) == []


def test_only_passing_tests_exit_0(tmp_path):
    proc, junit = orchestra_test(tmp_path, str(TESTS / "passing.test"))
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert verdicts(junit) == {"passes": "passed"}
    assert " * RESULT: SUCCESS" in proc.stdout
    assert (tmp_path / "results" / "rostest_pkg" / "rosunit-passes.xml").is_file()


def test_select_one_test_with_t(tmp_path):
    proc, junit = orchestra_test(tmp_path, str(TESTS / "verdicts.test"), "-t", "fails")
    assert proc.returncode == 1
    assert verdicts(junit) == {"fails": "failure"}


def test_unknown_t_name_is_a_user_error_exit_2(tmp_path):
    proc, _ = orchestra_test(tmp_path, str(TESTS / "verdicts.test"), "-t", "nope")
    assert proc.returncode == 2
    assert "no such test" in proc.stderr and "Traceback" not in proc.stderr


def test_bad_input_is_an_error_per_test_and_the_others_still_run(tmp_path):
    proc, junit = orchestra_test(tmp_path, str(TESTS / "bad_input.test"))
    assert proc.returncode == 1, proc.stdout + proc.stderr
    found = verdicts(junit)
    unnamed = next(name for name in found if name.startswith("<test> at "))
    assert found == {unnamed: "error", "missing_exe": "error", "bad_xml": "error",
                     "passes": "passed"}
    assert "bad_input.test:2: <test>: missing required attribute 'test-name'" in proc.stdout
    assert "bad_input.test:3:" in proc.stdout and "no_such_test.py" in proc.stdout
    assert "not valid XML" in proc.stdout
    assert " * ERRORS: 3" in proc.stdout
    assert "Traceback" not in proc.stdout + proc.stderr
    assert left_running(tmp_path) == []


def test_hztest_paramtest_publishtest_advertisetest_files_run_unchanged(tmp_path):
    proc, junit = orchestra_test(tmp_path, str(TESTS / "hz.test"))
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert verdicts(junit) == {"hztest_chatter": "passed", "paramtest_answer": "passed",
                               "publishtest_chatter": "passed",
                               "advertisetest_chatter": "passed"}


def test_bundled_hztest_fails_a_rate_outside_its_bounds(tmp_path):
    launch = tmp_path / "slow.test"
    launch.write_text((TESTS / "hz.test").read_text()
                      .replace('name="hz" value="10.0"', 'name="hz" value="50.0"'))
    proc, junit = orchestra_test(tmp_path, str(launch), "-t", "hztest_chatter")
    assert proc.returncode == 1
    assert verdicts(junit) == {"hztest_chatter": "failure"}
    assert "exceeded minimum" in proc.stdout


def real_rostest_verdicts(results: Path, stem: str) -> dict[str, str]:
    """Per test: its own rosunit file's verdict, else what rostest's runner recorded."""
    found = {}
    runner = etree.parse(str(results / f"rostest-test_{stem}.xml")).getroot()
    for case in runner.iter("testcase"):
        name = case.get("name")[len("test"):]
        kinds = {child.tag for child in case}
        own = results / f"rosunit-{name}.xml"
        if own.is_file():
            cases = parse_results(own.read_bytes(), name)
            kinds |= {c.verdict for c in cases}
        found[name] = ("error" if "error" in kinds else
                       "failure" if "failure" in kinds else "passed")
    return found


@pytest.mark.skipif(not shutil.which("rostest") or not Path("/usr/bin/python3").exists(),
                    reason="Debian's rostest (python3-rostest) is not installed")
def test_real_rostest_gives_the_same_verdicts_to_the_same_programs(tmp_path):
    env = env_for(tmp_path)
    env["ROS_PACKAGE_PATH"] = f"{PKG_ROOT}:/usr/share"
    env.pop("PYTHONPATH", None)       # the real tools run on Debian's Python and rospy
    real = subprocess.run(["rostest", "--results-base-dir", str(tmp_path / "real"),
                           str(TESTS / "verdicts.test")], env=env, cwd=tmp_path,
                          capture_output=True, text=True, timeout=150,
                          stdin=subprocess.DEVNULL)
    assert real.returncode != 0
    theirs = real_rostest_verdicts(tmp_path / "real" / "rostest_pkg", "verdicts")
    proc, junit = orchestra_test(tmp_path, str(TESTS / "verdicts.test"))
    ours = verdicts(junit)
    assert theirs["passes"] == ours["passes"] == "passed"
    assert theirs["fails"] == ours["fails"] == "failure"
    # past its time-limit: rostest's runner records an error, orchestra test a failure
    # (as the issue asks; docs/compat.md): both a test that did not pass
    assert theirs["hangs"] == "error" and ours["hangs"] == "failure"
    assert proc.returncode != 0


# --- results files: the forms tests write -------------------------------------------------

GTEST = b"""<?xml version="1.0" encoding="UTF-8"?>
<testsuites tests="3" failures="1" disabled="1" errors="0" name="AllTests">
  <testsuite name="Math" tests="3" failures="1" disabled="1" errors="0">
    <testcase name="adds" status="run" time="0.001" classname="Math"/>
    <testcase name="divides" status="run" time="0.002" classname="Math">
      <failure message="Value of: 1/0" type=""><![CDATA[math.cpp:12]]></failure>
    </testcase>
    <testcase name="DISABLED_slow" status="notrun" time="0" classname="Math"/>
  </testsuite>
</testsuites>"""

ROSUNIT = b"""<?xml version="1.0" encoding="utf-8"?><testsuite errors="1" failures="0"
name="unittest.suite.TestSuite" tests="2" time="0.1"><testcase classname="pkg.Case"
name="test_ok" time="0.0"/><testcase classname="pkg.Case" name="test_boom" time="0.0"><error
type="ValueError">boom</error></testcase></testsuite>"""


def test_gtest_results_give_each_case_its_verdict():
    cases = parse_results(GTEST, "math")
    assert [(c.name, c.verdict) for c in cases] == [
        ("adds", PASSED), ("divides", FAILURE), ("DISABLED_slow", SKIPPED)]
    assert cases[1].message == "Value of: 1/0" and "math.cpp:12" in cases[1].text


def test_rosunit_results_give_each_case_its_verdict():
    cases = parse_results(ROSUNIT, "t")
    assert [(c.name, c.verdict) for c in cases] == [("test_ok", PASSED), ("test_boom", ERROR)]


def test_a_suite_with_counts_but_no_cases_counts_them():
    data = b'<testsuite tests="2" failures="1" errors="0" name="s"></testsuite>'
    assert sorted(c.verdict for c in parse_results(data, "t")) == [FAILURE, PASSED]


@pytest.mark.parametrize("data", [b"", b"<testsuite", b"<html/>"])
def test_results_that_are_not_test_xml_are_refused(data):
    with pytest.raises(ResultsError):
        parse_results(data, "t")


def test_entities_in_results_are_not_expanded():
    data = b'<!DOCTYPE x [<!ENTITY a "aaaa">]><testsuite name="s">&a;</testsuite>'
    assert parse_results(data, "t") == []


def test_a_required_node_dying_during_a_test_fails_it(tmp_path):
    proc, junit = orchestra_test(tmp_path, str(TESTS / "required_dies.test"))
    assert proc.returncode == 1, proc.stdout + proc.stderr
    assert verdicts(junit) == {"outlived": "failure"}
    assert "required process /critical died" in proc.stdout
    assert left_running(tmp_path) == []


def test_retry_runs_a_failed_test_again_on_a_fresh_run(tmp_path):
    proc, junit = orchestra_test(tmp_path, str(TESTS / "retry.test"))
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert verdicts(junit) == {"flaky": "passed"}
    assert "failed, retrying. Retries left: 1" in proc.stderr


def test_ctrl_c_fails_the_running_test_skips_the_rest_reports_and_exits_130(tmp_path):
    out = tmp_path / "junit.xml"
    proc = subprocess.Popen([sys.executable, "-m", "orchestra", "test",
                             str(TESTS / "interrupted.test"), "--junit-xml", str(out),
                             "--results-dir", str(tmp_path / "results")],
                            env=env_for(tmp_path), cwd=tmp_path, stdin=subprocess.DEVNULL,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        assert proc.stderr is not None
        for line in proc.stderr:                        # the runner's progress lines
            if "running test [hangs]" in line:
                break
        proc.send_signal(signal.SIGINT)
        stdout, stderr = proc.communicate(timeout=60)
    finally:
        proc.kill()
        proc.communicate()
    assert proc.returncode == 130, stdout + stderr
    assert "test [hangs] was interrupted: SIGINT received" in stdout
    assert "orchestra: SIGINT received, tests stopped" in stderr
    root = etree.parse(str(out)).getroot()
    suites = {suite.get("name"): suite for suite in root.iter("testsuite")}
    assert suites["hangs"].find("testcase/failure") is not None
    skipped = suites["after"].find("testcase/skipped")
    assert skipped is not None
    assert left_running(tmp_path) == []
