"""/rosout for real: a node's loginfo reaches /rosout_agg and rosout.log when orchestra serves
the master (``orchestra launch`` embedded, ``orchestra core``); ``--no-rosout`` leaves it out.

Every master here is on a free ephemeral port; every process is killed by the fixtures.
"""
from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import psutil
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent / "node_fixtures"))
from harness import free_port  # noqa: E402

pytestmark = pytest.mark.timeout(60)

ORCHESTRA = [sys.executable, "-m", "orchestra"]

TALKER = '''#!{python}
import orchestra.node as node

node.init_node("talker")
i = 0
while not node.is_shutdown():
    node.loginfo("hello from talker %d", i)
    i += 1
    try:
        node.sleep(0.1)
    except node.ROSInterruptException:
        break
'''

LAUNCH = '<launch><node pkg="demo" type="talker" name="talker"/></launch>\n'


@pytest.fixture
def env(tmp_path):
    """A workspace with the talker node, a launch file, logs under tmp, and a free port."""
    nodes = tmp_path / "ws" / "demo" / "nodes"
    nodes.mkdir(parents=True)
    (tmp_path / "ws" / "demo" / "package.xml").write_text(
        "<package format='2'><name>demo</name><version>0.0.0</version><description>d"
        "</description><maintainer email='a@b.c'>a</maintainer><license>BSD</license></package>")
    talker = nodes / "talker"
    talker.write_text(TALKER.format(python=sys.executable))
    talker.chmod(0o755)
    (tmp_path / "t.launch").write_text(LAUNCH)
    environ = {k: v for k, v in os.environ.items()
               if k not in ("ROS_LOG_DIR", "ROS_NAMESPACE", "ROS_IP", "ROS_HOSTNAME",
                            "CMAKE_PREFIX_PATH")}
    environ.update(ROS_PACKAGE_PATH=str(tmp_path / "ws"), ROS_HOME=str(tmp_path / "home"),
                   ROS_MASTER_URI=f"http://127.0.0.1:{free_port()}/",
                   XDG_RUNTIME_DIR=str(tmp_path), PYTHONUNBUFFERED="1")
    return {"tmp": tmp_path, "env": environ, "talker": str(talker)}


@pytest.fixture
def spawn():
    """Popen in its own session; every process still alive at the end is killed with its group."""
    procs: list[subprocess.Popen] = []

    def start(argv, env, **kwargs) -> subprocess.Popen:
        proc = subprocess.Popen(argv, env=env, start_new_session=True, **kwargs)
        procs.append(proc)
        return proc

    yield start
    for proc in procs:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
        proc.wait(10)


def echo_one(environ, topic="/rosout_agg") -> str:
    """One message of ``topic`` as ``orchestra topic echo`` prints it (a real subscriber)."""
    done = subprocess.run([*ORCHESTRA, "topic", "echo", topic, "-n", "1"], env=environ,
                          capture_output=True, text=True, timeout=30)
    assert done.returncode == 0, done.stderr
    return done.stdout


def wait_for_file_text(path: Path, text: str, timeout: float = 15.0) -> str:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        content = path.read_text() if path.exists() else ""
        if text in content:
            return content
        time.sleep(0.1)
    raise AssertionError(f"{text!r} not in {path}: {content!r}")


def stop(proc: subprocess.Popen, timeout: float = 30) -> int:
    proc.send_signal(signal.SIGINT)
    return proc.wait(timeout)


def test_loginfo_reaches_rosout_agg_and_rosout_log_with_embedded_master(env, spawn):
    out = env["tmp"] / "launch.out"
    with open(out, "w") as fh:
        launch = spawn([*ORCHESTRA, "launch", str(env["tmp"] / "t.launch"), "--no-status",
                        "--disable-title"], env["env"], stdout=fh, stderr=subprocess.STDOUT)
    wait_for_file_text(out, "process[/talker]: started")     # the master is up by then
    got = echo_one(env["env"])
    assert 'name: "/talker"' in got and "hello from talker" in got
    latest = env["tmp"] / "home" / "log" / "latest"
    lines = wait_for_file_text(latest / "rosout.log", "hello from talker").splitlines()
    line = next(line for line in lines if "hello from talker" in line)
    assert line.split(" ")[1:3] == ["INFO", "/talker"]
    assert f"[{env['talker']}:" in line and "[topics: /rosout]" in line
    # respawn="true" as in roscore.xml: a killed rosout comes back and appends to its file
    pid = int(out.read_text().split("process[/rosout]: started with pid [")[1].split("]")[0])
    os.kill(pid, signal.SIGKILL)
    wait_for_file_text(out, "process[/rosout]: died")
    assert "hello from talker" in echo_one(env["env"])
    content = wait_for_file_text(latest / "rosout.log", "Node Startup", timeout=5)
    assert content.count("Node Startup") == 2 and content.index("hello from talker") < \
        content.rindex("Node Startup")
    assert stop(launch) == 0
    text = out.read_text()
    # /rosout started before the plan's node and counted first, as roslaunch's core node
    assert text.index("process[/rosout]: started") < text.index("process[/talker]: started")
    assert (latest / "rosout-1-stdout.log").exists() and (latest / "talker-2-stdout.log").exists()


def test_no_rosout_flag_starts_only_the_plan_nodes(env, spawn):
    out = env["tmp"] / "launch.out"
    with open(out, "w") as fh:
        launch = spawn([*ORCHESTRA, "launch", str(env["tmp"] / "t.launch"), "--no-status",
                        "--disable-title", "--no-rosout"], env["env"], stdout=fh,
                       stderr=subprocess.STDOUT)
    # /rosout would be spawned (and announced) before /talker: seeing /talker is enough
    wait_for_file_text(out, "process[/talker]: started")
    assert stop(launch) == 0
    assert "/rosout" not in out.read_text()
    assert sorted(p.name for p in (env["tmp"] / "home" / "log" / "latest").iterdir()) == [
        "talker-1-stderr.log", "talker-1-stdout.log"]


def test_core_serves_rosout_agg_and_stops_rosout_on_exit(env, spawn):
    core = spawn([*ORCHESTRA, "core", "-p", "0"], env["env"], stdout=subprocess.PIPE,
                 stderr=subprocess.PIPE, text=True)
    line = core.stdout.readline()
    assert line.startswith("ROS_MASTER_URI="), line
    node_env = {**env["env"], "ROS_MASTER_URI": line.strip().split("=", 1)[1]}
    spawn([env["talker"], "__name:=talker"], node_env, stdout=subprocess.DEVNULL)
    got = echo_one(node_env)
    assert 'name: "/talker"' in got and "hello from talker" in got
    rosout = [p for p in psutil.Process(core.pid).children()
              if any("rosout" in part for part in p.cmdline())]
    assert len(rosout) == 1
    core.send_signal(signal.SIGINT)
    out, err = core.communicate(timeout=30)
    assert core.returncode == 0, err
    assert not psutil.pid_exists(rosout[0].pid) or rosout[0].status() == psutil.STATUS_ZOMBIE
    run_dir = env["tmp"] / "home" / "log" / "latest"
    assert "hello from talker" in (run_dir / "rosout.log").read_text()


def test_a_launch_stopped_while_rosout_starts_ends_quietly(env, spawn):
    """SIGINT the moment /rosout is spawned (its interpreter still importing): it ends with
    the run, silently: no 'Fatal Python error', no traceback on the console."""
    (env["tmp"] / "empty.launch").write_text("<launch/>\n")
    for attempt in range(6):
        proc = spawn([*ORCHESTRA, "launch", str(env["tmp"] / "empty.launch"), "--no-status"],
                     {**env["env"], "ROS_MASTER_URI": f"http://127.0.0.1:{free_port()}/"},
                     stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        seen = []
        for line in proc.stdout:
            seen.append(line)
            if "process[/rosout]: started" in line:
                break
        proc.send_signal(signal.SIGINT)
        rest = proc.communicate(timeout=30)[0]
        console = "".join(seen) + rest
        assert proc.returncode == 0, console
        assert "Traceback" not in console and "Fatal Python error" not in console, \
            (attempt, console)
