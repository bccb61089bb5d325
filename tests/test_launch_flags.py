"""roslaunch's remaining flags on ``orchestra launch``: --pid, --core, --no-summary, -t,
--skip-log-check, -c/-u, and the SUMMARY block (compared with real roslaunch's)."""
from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
import xmlrpc.client
from pathlib import Path

import pytest

from orchestra.app.cli import log_size_warning
from orchestra.launch.summary import summary_value

sys.path.insert(0, str(Path(__file__).resolve().parent / "node_fixtures"))
from harness import ROS_PYTHON, demo_package, free_port, wait_for  # noqa: E402

pytestmark = pytest.mark.timeout(90)
REPO = Path(__file__).resolve().parent.parent
TURTLE_TF = REPO / "packages" / "turtle_tf" / "launch" / "turtle_tf_demo.launch"
LAUNCH = """<launch>
  <param name="long" value="a value longer than twenty characters"/>
  <node pkg="demo" type="sleeper" name="a"/>
  <group ns="g"><node pkg="demo" type="sleeper" name="b"/></group>
</launch>
"""


@pytest.fixture
def env(tmp_path):
    demo_package(tmp_path / "ws", {"sleeper": "#!/bin/sh\nexec sleep 1000\n"})
    (tmp_path / "x.launch").write_text(LAUNCH)
    environ = {k: v for k, v in os.environ.items() if k not in ("ROS_LOG_DIR", "ROS_NAMESPACE")}
    environ.update(ROS_PACKAGE_PATH=str(tmp_path / "ws"), ROS_HOME=str(tmp_path / "home"),
                   ROS_MASTER_URI=f"http://localhost:{free_port()}/",
                   XDG_RUNTIME_DIR=str(tmp_path))
    return environ


def add_node(tmp_path, name: str, script: str) -> None:
    """One more executable in the env fixture's demo package."""
    path = tmp_path / "ws" / "demo" / "nodes" / name
    path.write_text(script)
    path.chmod(0o755)


def start(env, *args: str) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-m", "orchestra", "launch", *args], env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def stop(proc: subprocess.Popen) -> tuple[str, str]:
    if proc.poll() is None:
        proc.send_signal(signal.SIGINT)
    return proc.communicate(timeout=30)


def master_up(uri: str) -> bool:
    try:
        with xmlrpc.client.ServerProxy(uri) as proxy:
            return proxy.getPid("/t")[0] == 1
    except OSError:
        return False


def launch_running(env) -> bool:
    """The launch answers on its status socket with every node RUNNING (signals are ours)."""
    from orchestra.supervise.status import running_launches

    directory = os.path.join(env["XDG_RUNTIME_DIR"], "orchestra")
    return os.path.isdir(directory) and any(
        doc["nodes"] and all(n["state"] == "RUNNING" for n in doc["nodes"])
        for doc in running_launches(directory))


def test_pid_file_is_written_for_the_run_and_removed_after(env, tmp_path):
    pid_file = tmp_path / "run" / "launch.pid"
    proc = start(env, str(tmp_path / "x.launch"), "--no-status", "--pid", str(pid_file))
    try:
        wait_for(lambda: launch_running(env))
        assert int(pid_file.read_text()) == proc.pid
    finally:
        stop(proc)
    assert proc.returncode == 0 and not pid_file.exists()


def test_core_runs_a_master_alone_with_roscores_pid_file(env, tmp_path):
    port = free_port()
    proc = start(env, "--core", "-p", str(port))
    uri = f"http://127.0.0.1:{port}/"
    pid_file = tmp_path / "home" / f"roscore-{port}.pid"
    try:
        wait_for(lambda: master_up(uri))
        assert int(pid_file.read_text()) == proc.pid
        with xmlrpc.client.ServerProxy(uri) as master:
            assert master.getParam("/t", "/rosversion")[0] == 1

            def graph_nodes() -> set[str]:
                publishers, subscribers, _ = master.getSystemState("/t")[2]
                return {n for _, names in publishers + subscribers for n in names}

            wait_for(lambda: "/rosout" in graph_nodes())
            assert graph_nodes() == {"/rosout"}
    finally:
        out, err = stop(proc)
    assert proc.returncode == 0, err
    assert f"ROS_MASTER_URI={uri}" in out and not pid_file.exists()


@pytest.mark.parametrize("args, message", [
    (("--core", "x.launch"), "launch files are not allowed with --core"),
    (("--core", "--wait"), "--wait cannot be used with --core"),
    (("-c", "child", "x.launch"), "no child mode"),
    (("-u", "http://h:1/", "x.launch"), "no child mode"),
])
def test_flags_roslaunch_refuses_or_orchestra_cannot_honour_are_clear_errors(env, args, message):
    cli = subprocess.run([sys.executable, "-m", "orchestra", "launch", *args], env=env,
                         capture_output=True, text=True, timeout=30)
    assert cli.returncode == 2 and message in cli.stderr
    assert "Traceback" not in cli.stderr


def test_summary_is_printed_before_the_run_and_hidden_by_no_summary(env, tmp_path):
    proc = start(env, str(tmp_path / "x.launch"), "--no-status", "-t", "5")
    try:
        wait_for(lambda: launch_running(env))
    finally:
        text, _ = stop(proc)
    assert text.startswith("\nSUMMARY\n========\n")
    assert " * /long: a value longer th...\n" in text
    assert "NODES\n  /\n    a (demo/sleeper)\n  /g/\n    b (demo/sleeper)\n" in text
    assert f"\nROS_MASTER_URI={env['ROS_MASTER_URI']}\n" in text
    proc = start(env, str(tmp_path / "x.launch"), "--no-status", "--no-summary")
    try:
        wait_for(lambda: launch_running(env))
    finally:
        out, _ = stop(proc)
    assert "SUMMARY" not in out and "NODES" not in out


def test_summary_values_are_cut_and_unprintable_ones_hidden_as_roslaunch_does():
    assert summary_value("x" * 25) == "x" * 17 + "..."
    assert summary_value("noetic\n") == "noetic"
    assert summary_value("a\x01b") == "<...>"
    assert summary_value(True) == "True" and summary_value([1, 2]) == "[1, 2]"


def test_log_check_warns_past_the_limit_only(tmp_path):
    (tmp_path / "run1").mkdir()
    (tmp_path / "run1" / "a.log").write_bytes(b"x" * 2000)
    assert log_size_warning(str(tmp_path), limit=5000) is None
    warning = log_size_warning(str(tmp_path), limit=1000)
    assert warning and str(tmp_path) in warning and "--skip-log-check" in warning


def _ros_env(extra: dict[str, str]) -> dict[str, str]:
    env = {k: v for k, v in os.environ.items()
           if not k.startswith(("PYTHON", "ROS_", "VIRTUAL_ENV", "PYENV"))}
    env.update(PYTHONUNBUFFERED="1", **extra)
    return env


def _summary_block(out: str) -> str:
    """The SUMMARY block of a launch's stdout, with the two values that name the ROS build
    (Debian's /rosdistro and /rosversion vs the noetic orchestra emulates) masked."""
    block = out[out.index("\nSUMMARY\n"):]
    block = block[:block.index("\nROS_MASTER_URI=")] if "\nROS_MASTER_URI=" in block \
        else block[:block.index("\n\n", block.index("NODES")) + 1]
    return re.sub(r"( \* /ros(?:distro|version): ).*", r"\1<build>", block)


@pytest.mark.skipif(not os.access(ROS_PYTHON, os.X_OK)
                    or subprocess.run([ROS_PYTHON, "-c", "import roslaunch"],
                                      capture_output=True).returncode != 0,
                    reason="Debian's roslaunch (python3-roslaunch) is not installed")
def test_summary_equals_real_roslaunchs_for_the_turtle_tf_demo(tmp_path):
    """Real ``roslaunch`` (Debian's CLI) and ``orchestra launch`` of the same file print the
    same SUMMARY; roslaunch is stopped as soon as it printed it (its nodes need orchestra)."""
    packages = str(REPO / "packages")
    real_out = tmp_path / "roslaunch.out"
    with open(real_out, "w") as sink:
        real = subprocess.Popen(
            [ROS_PYTHON, "/usr/bin/roslaunch", str(TURTLE_TF)], stdout=sink,
            stderr=subprocess.STDOUT,
            env=_ros_env({"ROS_PACKAGE_PATH": packages, "ROS_HOME": str(tmp_path / "ros"),
                          "ROS_MASTER_URI": f"http://localhost:{free_port()}/"}))
        try:
            wait_for(lambda: "started with pid" in real_out.read_text(), timeout=60)
        finally:
            real.send_signal(signal.SIGINT)
            real.wait(timeout=60)
    real_text = real_out.read_text()
    uri = f"http://localhost:{free_port()}/"
    ours = start(dict(os.environ, ROS_PACKAGE_PATH=packages, ROS_MASTER_URI=uri,
                      ROS_HOME=str(tmp_path / "orch"), XDG_RUNTIME_DIR=str(tmp_path)),
                 str(TURTLE_TF), "--no-status", "--screen")
    try:
        wait_for(lambda: launch_running({"XDG_RUNTIME_DIR": str(tmp_path)}), timeout=30)
    finally:
        out, _ = stop(ours)
    expected = _summary_block(real_text)
    assert "turtle1_tf_broadcaster (turtle_tf/turtle_tf_broadcaster.py)" in expected
    assert _summary_block(out) == expected
    print(expected)


def test_undeclared_command_line_arg_is_warned_with_a_suggestion(env, tmp_path):
    add_node(tmp_path, "done", "#!/bin/sh\nexit 0\n")
    (tmp_path / "args.launch").write_text(
        '<launch><arg name="driver" default="teleop"/><group><arg name="speed" default="1"/>'
        '</group><node pkg="demo" type="done" name="job" required="true"/></launch>')
    cli = subprocess.run([sys.executable, "-m", "orchestra", "launch", str(tmp_path / "args.launch"),
                          "drivr:=auto", "speed:=2", "--no-status", "--no-rosout"], env=env,
                         capture_output=True, text=True, timeout=60)
    assert cli.returncode == 0, cli.stderr
    assert ("orchestra: warning: arg 'drivr' is not declared by the launch file (roslaunch "
            "ignores it) (did you mean driver?)") in cli.stderr
    assert "'speed'" not in cli.stderr


def test_ui_without_a_terminal_falls_back_to_plain_output(env, tmp_path):
    add_node(tmp_path, "done", "#!/bin/sh\necho finished\n")
    (tmp_path / "job.launch").write_text(
        '<launch><node pkg="demo" type="done" name="job" required="true" output="screen"/>'
        '</launch>')
    cli = subprocess.run([sys.executable, "-m", "orchestra", "launch", str(tmp_path / "job.launch"),
                          "--ui", "--no-rosout", "--no-summary"], env=env, stdin=subprocess.DEVNULL,
                         capture_output=True, text=True, timeout=60)
    assert cli.returncode == 0, cli.stderr
    assert "--ui: stdin and stdout are not both a terminal; plain output" in cli.stderr
    assert "[/job] finished\n" in cli.stdout and "\x1b[" not in cli.stdout
