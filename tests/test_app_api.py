"""The Python API (``orchestra.launch_file``) and the ``launch`` pytest fixture.

The same LaunchRun backs ``orchestra launch``; here it is driven from Python: start, wait
for the graph, kill and restart nodes, stop with nothing left behind.
"""
from __future__ import annotations

import os
import subprocess
import sys
import textwrap
from pathlib import Path

import psutil
import pytest

import orchestra
from orchestra.errors import OrchestraError
from orchestra.supervise.process import State

HERE = Path(__file__).resolve().parent
SIM = HERE / "app_files" / "respawning_sim.launch"

pytestmark = pytest.mark.timeout(120)


@pytest.fixture(autouse=True)
def headless(monkeypatch):
    """The bundled packages and no window, whatever the developer's shell has."""
    for name in ("DISPLAY", "ROS_PACKAGE_PATH", "CMAKE_PREFIX_PATH", "ROS_NAMESPACE"):
        monkeypatch.delenv(name, raising=False)


def wait_until(predicate, timeout: float = 20.0):
    sys.path.insert(0, str(HERE / "node_fixtures"))
    import harness

    return harness.wait_for(predicate, timeout=timeout)


def children_left() -> list[psutil.Process]:
    """This process's descendants, minus zombies already gone."""
    return [p for p in psutil.Process().children(recursive=True)
            if p.is_running() and p.status() != psutil.STATUS_ZOMBIE]


def test_fixture_runs_turtlesim_kill_respawns_and_stop_leaves_nothing(launch):
    run = launch(SIM)
    run.wait_for(topic="/turtle1/pose", service="/spawn", node="/sim", timeout=30)
    assert "/sim" in run.nodes
    first = run.process("/sim")
    assert first.state == State.RUNNING and first.pid and first.restarts == 0
    assert run.kill("/sim")
    wait_until(lambda: run.process("sim").restarts == 1
               and run.process("sim").state == State.RUNNING)
    assert run.process("/sim").pid != first.pid
    run.wait_for(topic="/turtle1/pose", timeout=30)
    report = run.stop()
    assert report.exit_code == 0
    assert report.processes["/sim"].state == State.EXITED
    assert not psutil.pid_exists(run.process("/sim").pid) or \
        psutil.Process(run.process("/sim").pid).status() == psutil.STATUS_ZOMBIE
    assert children_left() == []


def test_restart_stops_in_order_and_starts_again(launch):
    run = launch(SIM)
    run.wait_for(node="/sim", timeout=30)
    before = run.process("/sim").pid
    run.restart("/sim")
    wait_until(lambda: run.process("/sim").state == State.RUNNING
               and run.process("/sim").pid != before)
    assert run.process("/sim").restarts == 1
    assert run.stop().processes["/sim"].state == State.EXITED


def make_package(root: Path, name: str, scripts: dict[str, str]) -> Path:
    """A package ``name`` under ``root`` whose scripts are the given Python sources."""
    pkg = root / name
    (pkg / "scripts").mkdir(parents=True)
    (pkg / "package.xml").write_text(f"<package format='2'><name>{name}</name>"
                                     "<version>0.0.0</version><description>t</description>"
                                     "<maintainer email='a@b.c'>a</maintainer>"
                                     "<license>BSD</license></package>")
    for script, source in scripts.items():
        path = pkg / "scripts" / script
        path.write_text("#!/usr/bin/env python3\n" + source)
        path.chmod(0o755)
    return root


def test_launch_file_context_manager_has_its_own_master_and_reports_per_node(tmp_path,
                                                                              monkeypatch):
    monkeypatch.setenv("ROS_PACKAGE_PATH", str(make_package(tmp_path / "src", "probe",
                                                            {"done.py": "raise SystemExit(3)\n"})))
    launch_path = tmp_path / "one.launch"
    launch_path.write_text(textwrap.dedent("""\
        <launch>
          <arg name="code" default="0"/>
          <param name="answer" value="$(arg code)"/>
          <node pkg="probe" type="done.py" name="done"/>
        </launch>"""))
    with orchestra.launch_file(launch_path, args={"code": 42}, ros_home=str(tmp_path),
                               no_rosout=True) as run:
        assert run.master_uri != os.environ.get("ROS_MASTER_URI")
        run.wait_for(param="/answer", timeout=10)
        wait_until(lambda: run.process("/done").state == State.EXITED)
        assert run.wait(timeout=0) is None   # an embedded master runs until stopped
    assert run.report is not None
    assert run.report.processes["/done"].exit_code == 3
    assert run.log_dir is not None and run.log_dir.startswith(str(tmp_path))


def test_reusing_a_master_leaves_it_running(master, tmp_path):
    launch_path = tmp_path / "p.launch"
    launch_path.write_text('<launch><param name="reused" value="yes"/></launch>')
    with orchestra.launch_file(launch_path, master=master.uri, ros_home=str(tmp_path)) as run:
        assert run.master_uri == master.uri
        run.wait_for(param="/reused", timeout=5)
    assert master.running
    assert master.params.get("/reused") == "yes"


def test_launch_mistakes_raise_before_anything_starts(tmp_path):
    bad = tmp_path / "bad.launch"
    bad.write_text('<launch>\n  <node pkg="no_such_pkg" type="nope" name="n"/>\n</launch>')
    run = orchestra.launch_file(bad, ros_home=str(tmp_path))
    with pytest.raises(OrchestraError) as info:
        run.start()
    assert "bad.launch:2" in str(info.value)
    assert run.master is None and children_left() == []


def test_importing_orchestra_does_not_import_the_app_layer():
    code = "import orchestra, sys; print(any(m.startswith('orchestra.app') for m in sys.modules))"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout
    assert out.strip() == "False"


def test_eight_fixture_runs_in_parallel_under_xdist_do_not_collide(tmp_path):
    """Eight turtlesim runs at once, one per xdist worker: own masters, run ids, ROS_HOMEs."""
    pytest.importorskip("xdist")
    cases = HERE / "app_files" / "xdist_sim_cases.py"
    proc = subprocess.run([sys.executable, "-m", "pytest", "-q", "-n", "8", "-p",
                           "no:cacheprovider", "--basetemp", str(tmp_path / "base"),
                           str(cases)], cwd=HERE.parent, capture_output=True, text=True,
                          timeout=300, stdin=subprocess.DEVNULL)
    assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-3000:]
    assert "8 passed" in proc.stdout
