"""``orchestra launch`` dump modes, through the real command line."""
import json
import os
import signal
import subprocess
import sys
import time

import pytest


@pytest.fixture
def ws(tmp_path):
    pkg = tmp_path / "ws" / "demo"
    (pkg / "launch" / "sub").mkdir(parents=True)
    (pkg / "package.xml").write_text("<package><name>demo</name></package>")
    (pkg / "launch" / "sub" / "main.launch").write_text(
        '<launch>\n  <arg name="rate" default="10" doc="publish rate"/>\n'
        '  <arg name="robot"/>\n'
        '  <param name="rate" value="$(arg rate)"/>\n'
        '  <param name="robot" value="$(arg robot)"/>\n'
        '  <param name="blob" binfile="$(dirname)/main.launch"/>\n'
        '  <group ns="g"><node name="talker" pkg="demo" type="talk" args="-v"/></group>\n'
        '  <include file="$(dirname)/inc.launch"/>\n</launch>\n')
    (pkg / "launch" / "sub" / "inc.launch").write_text(
        '<launch><node name="listener" pkg="demo" type="listen"/></launch>\n')
    return tmp_path / "ws"


def orchestra(ws, *words, stdin=None):
    env = {"PATH": os.environ["PATH"], "ROS_PACKAGE_PATH": str(ws), "ROS_DISTRO": "noetic",
           "ROS_HOME": str(ws / ".ros")}
    return subprocess.run([sys.executable, "-m", "orchestra", "launch", *words], env=env,
                          input=stdin, capture_output=True, text=True, timeout=60)


@pytest.mark.timeout(120)
def test_pkg_file_form_finds_the_file_anywhere_in_the_package(ws):
    proc = orchestra(ws, "demo", "main.launch", "robot:=pr2", "--nodes")
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.split() == ["/g/talker", "/listener"]


@pytest.mark.timeout(120)
def test_dump_plan_is_json_with_binary_params_and_cli_args(ws):
    proc = orchestra(ws, "demo", "main.launch", "robot:=pr2", "rate:=5", "3d:=x",
                     "--dump-plan", "--no-exec")
    assert proc.returncode == 0, proc.stderr
    plan = json.loads(proc.stdout)
    assert plan["params"]["/rate"] == 5
    assert set(plan["params"]["/blob"]) == {"__binary_b64__"}
    assert [n["name"] for n in plan["nodes"]] == ["talker", "listener"]
    assert len(plan["files_loaded"]) == 2


@pytest.mark.timeout(120)
def test_dump_params_prints_yaml_without_roscore_params(ws):
    import yaml
    proc = orchestra(ws, "demo", "main.launch", "robot:=x", "--dump-params")
    assert proc.returncode == 0, proc.stderr
    params = yaml.safe_load(proc.stdout)
    assert params["/rate"] == 10 and "/rosversion" not in params


@pytest.mark.timeout(120)
def test_dump_params_ends_with_an_empty_line_like_roslaunch(ws):
    # roslaunch print()s the YAML document, which already ends in a newline
    proc = orchestra(ws, "demo", "main.launch", "robot:=x", "--dump-params")
    assert proc.stdout.endswith("\n\n") and not proc.stdout.endswith("\n\n\n")


@pytest.mark.timeout(120)
def test_files_find_node_and_ros_args(ws):
    files = orchestra(ws, "demo", "main.launch", "robot:=x", "--files")
    assert [os.path.basename(f) for f in files.stdout.split()] == ["main.launch", "inc.launch"]
    found = orchestra(ws, "demo", "main.launch", "robot:=x", "--find-node", "/listener")
    assert found.stdout.strip().endswith("inc.launch")
    args = orchestra(ws, "demo", "main.launch", "--ros-args")
    assert args.returncode == 0, args.stderr
    assert "Required Arguments:\n  robot: undocumented" in args.stdout
    assert '  rate (default "10"): publish rate' in args.stdout


@pytest.mark.timeout(120)
def test_missing_required_arg_is_a_located_error(ws):
    proc = orchestra(ws, "demo", "main.launch", "--dump-plan")
    assert proc.returncode == 2 and "Traceback" not in proc.stderr
    assert "main.launch:5" in proc.stderr and "'robot'" in proc.stderr


@pytest.mark.timeout(120)
def test_stdin_launch_file(ws):
    proc = orchestra(ws, "-", "--dump-params", stdin='<launch><param name="x" value="1"/></launch>')
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip() == "/x: 1"


@pytest.mark.parametrize("front", [[], ["-v"]], ids=["without-click", "through-click"])
def test_ctrl_c_during_a_command_param_of_dump_params_ends_it_at_once(tmp_path, front):
    """A dump starts nothing, so a Ctrl-C while a slow ``command=`` runs ends it with 130,
    the command's process killed, no traceback (it used to be recorded for a supervisor
    that a dump never has: the dump went on and exited 0)."""
    pid_file = tmp_path / "pid"
    launch = tmp_path / "slow.launch"
    launch.write_text('<launch>\n  <param name="x" command="sh -c \'echo $$ > '
                      f'{pid_file}; exec sleep 60\'"/>\n</launch>\n')
    env = {**os.environ, "ROS_HOME": str(tmp_path / ".ros")}
    proc = subprocess.Popen([sys.executable, "-m", "orchestra", *front, "launch",
                             "--dump-params", str(launch)], env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        deadline = time.monotonic() + 30
        while not (pid_file.exists() and pid_file.read_text().strip()):
            assert proc.poll() is None and time.monotonic() < deadline, proc.communicate()
            time.sleep(0.02)
        command_pid = int(pid_file.read_text())
        proc.send_signal(signal.SIGINT)
        out, err = proc.communicate(timeout=30)
    finally:
        proc.kill()
    assert proc.returncode == 130, err
    assert "Traceback" not in err and out == ""
    with pytest.raises(ProcessLookupError):
        os.kill(command_pid, 0)


def test_an_unreadable_declared_encoding_is_one_located_line_and_exit_2(tmp_path):
    launch = tmp_path / "bogus.launch"
    launch.write_text('<?xml version="1.0" encoding="bogus"?>\n<launch/>\n')
    proc = subprocess.run([sys.executable, "-m", "orchestra", "launch", "--dump-params",
                           str(launch)], capture_output=True, text=True, timeout=60)
    assert proc.returncode == 2
    assert proc.stderr.startswith(f"orchestra: error: {launch}:1: invalid XML: ")
    assert "Traceback" not in proc.stderr
