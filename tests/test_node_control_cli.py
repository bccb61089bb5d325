"""``orchestra node stop|start|restart`` and ``orchestra status`` against real launches."""
from __future__ import annotations

import os
import signal
import subprocess
import sys
from pathlib import Path

import pytest

pytestmark = pytest.mark.timeout(90)

sys.path.insert(0, str(Path(__file__).resolve().parent / "node_fixtures"))
from harness import demo_package, free_port, wait_for  # noqa: E402

LAUNCH = """<launch>
  <node pkg="demo" type="sleeper" name="a"/>
  <node pkg="demo" type="sleeper" name="b" required="true"/>
  <group ns="g">
    <node pkg="demo" type="sleeper" name="c"/>
  </group>
</launch>
"""


@pytest.fixture
def env(tmp_path):
    pkg = demo_package(tmp_path / "ws", {"sleeper": "#!/bin/sh\nexec sleep 1000\n"})
    (pkg / "launch").mkdir()
    (pkg / "launch" / "demo.launch").write_text(LAUNCH)
    environ = {k: v for k, v in os.environ.items()
               if k not in ("ROS_LOG_DIR", "ROS_NAMESPACE", "CMAKE_PREFIX_PATH")}
    environ.update(ROS_PACKAGE_PATH=str(tmp_path / "ws"), ROS_HOME=str(tmp_path / "home"),
                   ROS_MASTER_URI=f"http://localhost:{free_port()}/",
                   XDG_RUNTIME_DIR=str(tmp_path))
    return environ


def orchestra(env, *args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "orchestra", *args], env=env,
                          capture_output=True, text=True, timeout=60)


class Launch:
    def __init__(self, env):
        self.env = env
        self.proc = subprocess.Popen(
            [sys.executable, "-m", "orchestra", "launch", "demo", "demo.launch", "--no-status",
             "--no-rosout"], env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
            text=True)
        wait_for(lambda: self.states() and all(s == "RUNNING" for s, _ in self.states().values()),
                 timeout=30)

    def states(self) -> dict[str, tuple[str, int | None]]:
        import json

        out = orchestra(self.env, "status", "--json").stdout
        launches = json.loads(out) if out.strip() else []
        return {n["name"]: (n["state"], n["pid"]) for n in launches[0]["nodes"]} \
            if launches else {}

    def close(self) -> str:
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGINT)
        out, _ = self.proc.communicate(timeout=30)
        return out


@pytest.fixture
def launch(env):
    run = Launch(env)
    yield run
    run.close()


def test_node_restart_stop_start_through_the_cli(env, launch):
    before = launch.states()
    cli = orchestra(env, "node", "restart", "/a")
    assert cli.returncode == 0, cli.stderr
    after = launch.states()
    assert after["/a"][0] == "RUNNING" and after["/a"][1] != before["/a"][1]
    assert after["/b"] == before["/b"] and after["/g/c"] == before["/g/c"]
    assert f"pid {before['/a'][1]} -> {after['/a'][1]}" in cli.stdout

    cli = orchestra(env, "node", "stop", "a")
    assert cli.returncode == 0 and "/a: STOPPED" in cli.stdout
    status = orchestra(env, "status")
    assert "stopped by hand" in status.stdout and "REASON" in status.stdout
    assert launch.proc.poll() is None

    cli = orchestra(env, "node", "start", "/a")
    assert cli.returncode == 0 and launch.states()["/a"][0] == "RUNNING"


def test_stopping_a_required_node_needs_force(env, launch):
    cli = orchestra(env, "node", "stop", "/b")
    assert cli.returncode == 1 and "required" in cli.stderr and "--force" in cli.stderr
    assert launch.states()["/b"][0] == "RUNNING"
    cli = orchestra(env, "node", "stop", "--force", "/b")
    assert cli.returncode == 0 and launch.states()["/b"][0] == "STOPPED"
    assert launch.proc.poll() is None


def test_unknown_node_is_exit_2_with_did_you_mean_and_nothing_done(env, launch):
    before = launch.states()
    cli = orchestra(env, "node", "restart", "/a", "/g/cc")
    assert cli.returncode == 2
    assert cli.stderr.strip() == ("orchestra: error: no node /g/cc in this launch "
                                  "(did you mean /g/c?)")
    assert launch.states() == before


def test_status_shows_only_the_launch_at_ros_master_uri(env, launch):
    other_env = dict(env, ROS_MASTER_URI=f"http://localhost:{free_port()}/")
    other = Launch(other_env)
    try:
        mine = orchestra(env, "status")
        theirs = orchestra(other_env, "status")
        both = orchestra(env, "status", "--all")
    finally:
        other.close()
    def heads(out: str) -> list[str]:
        return [line for line in out.splitlines() if line.startswith("launch ")]

    assert len(heads(mine.stdout)) == 1 and env["ROS_MASTER_URI"] in mine.stdout
    assert len(heads(theirs.stdout)) == 1 and other_env["ROS_MASTER_URI"] in theirs.stdout
    assert len(heads(both.stdout)) == 2
    nobody = orchestra(dict(env, ROS_MASTER_URI=f"http://localhost:{free_port()}/"), "status")
    assert nobody.returncode == 1 and "orchestra status --all" in nobody.stderr


def test_node_names_of_the_running_launch_complete(env, launch):
    environ = dict(env, _ORCHESTRA_COMPLETE="bash_complete",
                   COMP_WORDS="orchestra node restart /g", COMP_CWORD="3")
    out = subprocess.run([sys.executable, "-m", "orchestra"], env=environ,
                         capture_output=True, text=True, timeout=60).stdout
    assert out.splitlines() == ["plain,/g/c"]


def test_control_reaches_every_launch_sharing_the_master(env, tmp_path):
    import json

    core = subprocess.Popen([sys.executable, "-m", "orchestra", "core", "--no-rosout"],
                            env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    second = tmp_path / "ws" / "demo" / "launch" / "second.launch"
    second.write_text('<launch><node pkg="demo" type="sleeper" name="x"/>'
                      '<group ns="g"><node pkg="demo" type="sleeper" name="y"/></group></launch>')
    runs = []
    try:
        wait_for(lambda: orchestra(env, "param", "get", "/rosversion").returncode == 0)
        runs.append(Launch(env))
        runs.append(subprocess.Popen([sys.executable, "-m", "orchestra", "launch", "demo",
                                      "second.launch", "--no-status"], env=env,
                                     stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL))

        def everyone() -> dict:
            docs = json.loads(orchestra(env, "status", "--json").stdout or "[]")
            return {n["name"]: (n["state"], n["pid"]) for d in docs for n in d["nodes"]}

        wait_for(lambda: len(everyone()) == 5
                 and all(s == "RUNNING" for s, _ in everyone().values()), timeout=30)
        before = everyone()
        cli = orchestra(env, "node", "restart", "/g")
        assert cli.returncode == 0, cli.stderr
        after = everyone()
        assert after["/g/c"][1] != before["/g/c"][1] and after["/g/y"][1] != before["/g/y"][1]
        assert after["/a"] == before["/a"] and after["/x"] == before["/x"]
        cli = orchestra(env, "node", "stop", "/x")
        assert cli.returncode == 0 and "/x: STOPPED" in cli.stdout, cli.stdout + cli.stderr
    finally:
        if runs:
            runs[0].close()
        for proc in (*runs[1:], core):
            proc.send_signal(signal.SIGINT)
            proc.wait(timeout=30)
