"""``serve_plan``: a hand-built LaunchPlan run for real (embedded master on a free port)."""
from __future__ import annotations

import json
import os
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

from orchestra.app.cli import options_from_cli, serve_plan
from orchestra.errors import OrchestraError
from orchestra.launch.plan import LaunchPlan, Machine, Node
from orchestra.supervise.command import node_argv
from orchestra.supervise.output import Screen
from orchestra.supervise.process import OutputMode, ProcessSpec, State
from orchestra.supervise.status import ProcessStats, StatusServer, query, snapshot
from orchestra.supervise.supervisor import Supervisor

sys.path.insert(0, str(Path(__file__).resolve().parent / "node_fixtures"))
from harness import free_port  # noqa: E402

pytestmark = pytest.mark.timeout(60)

PROBE = r'''#!/usr/bin/env python3
"""Records how it was started, reads params from the master, then behaves as asked."""
import json, os, sys, time, xmlrpc.client
master = xmlrpc.client.ServerProxy(os.environ["ROS_MASTER_URI"])
name = [a for a in sys.argv if a.startswith("__name:=")][0][8:]
record = {"argv": sys.argv, "cwd": os.getcwd(),
          "env": {k: os.environ.get(k) for k in ("ROS_MASTER_URI", "ROS_NAMESPACE", "NODE_ENV")},
          "param": master.getParam("/probe", "/p")[2],
          "run_id": master.getParam("/probe", "/run_id")[2]}
with open(os.path.join(os.environ["PROBE_OUT"], name + ".json"), "w") as fh:
    json.dump(record, fh)
mode = os.environ.get("PROBE_MODE_" + name, "exit0")
if mode == "sleep":
    time.sleep(100)
sys.exit(int(mode[4:]))
'''


@pytest.fixture
def run_env(tmp_path, monkeypatch):
    """A workspace with the probe node and a master already up at ROS_MASTER_URI."""
    from orchestra.master import start_master

    env = _workspace(tmp_path, monkeypatch)
    master = start_master("127.0.0.1", env["port"])
    yield env
    master.shutdown()


@pytest.fixture
def no_master_env(tmp_path, monkeypatch):
    """The same workspace with nobody at ROS_MASTER_URI: orchestra embeds the master."""
    return _workspace(tmp_path, monkeypatch)


def _workspace(tmp_path, monkeypatch):
    ws = tmp_path / "ws"
    nodes = ws / "demo" / "nodes"
    nodes.mkdir(parents=True)
    (ws / "demo" / "package.xml").write_text(
        "<package format='2'><name>demo</name><version>0.0.0</version><description>d"
        "</description><maintainer email='a@b.c'>a</maintainer><license>BSD</license></package>")
    probe = nodes / "probe"
    probe.write_text(PROBE.replace("/usr/bin/env python3", sys.executable))
    probe.chmod(0o755)
    out = tmp_path / "out"
    out.mkdir()
    port = free_port()
    for key in ("ROS_LOG_DIR", "ROS_NAMESPACE", "CMAKE_PREFIX_PATH"):
        monkeypatch.delenv(key, raising=False)
    monkeypatch.setenv("ROS_PACKAGE_PATH", str(ws))
    monkeypatch.setenv("ROS_HOME", str(tmp_path / "home"))
    monkeypatch.setenv("ROS_MASTER_URI", f"http://localhost:{port}/")
    monkeypatch.setenv("XDG_RUNTIME_DIR", str(tmp_path))
    monkeypatch.setenv("PROBE_OUT", str(out))
    return {"tmp": tmp_path, "probe": str(probe), "out": out, "port": port}


def record(run_env, name):
    return json.loads((run_env["out"] / f"{name}.json").read_text())


def run_plan(plan, options):
    """What ``orchestra launch`` does with a plan and its flags (click's keyword arguments)."""
    return serve_plan(plan, options_from_cli(options))


OPTS = {"run_id": "testrun", "status_view": False, "disable_title": True}


def test_node_runs_with_roslaunch_argv_env_cwd_and_sees_params(run_env):
    node = Node("demo", "probe", "probe", "/robot/", args="a 'b c'",
                remap_args=(("in", "/abs"),), env_args=(("NODE_ENV", "n1"),))
    plan = LaunchPlan(params={"/p": 42}, nodes=(node,))
    assert run_plan(plan, OPTS) == 0
    got = record(run_env, "probe")
    log_dir = run_env["tmp"] / "home" / "log" / "testrun"
    assert got["argv"][1:] == node_argv(node, run_env["probe"],
                                        log_file=str(log_dir / "robot-probe-1.log"))[1:]
    assert got["env"] == {"ROS_MASTER_URI": f"http://localhost:{run_env['port']}/",
                          "ROS_NAMESPACE": "/robot", "NODE_ENV": "n1"}
    assert got["cwd"] == str(run_env["tmp"] / "home")
    assert got["param"] == 42 and got["run_id"] == "testrun"
    assert (run_env["tmp"] / "home" / "log" / "latest").resolve() == log_dir


def test_cwd_node_runs_in_the_executable_directory(run_env):
    plan = LaunchPlan(nodes=(Node("demo", "probe", "probe", cwd="node",
                                  launch_prefix="env"),))
    assert run_plan(plan, OPTS) == 0
    assert record(run_env, "probe")["cwd"] == os.path.dirname(run_env["probe"])


def test_required_node_death_exits_nonzero_naming_the_node(run_env, monkeypatch, capsys):
    monkeypatch.setenv("PROBE_MODE_vital", "exit5")
    monkeypatch.setenv("PROBE_MODE_idle", "sleep")
    plan = LaunchPlan(nodes=(Node("demo", "probe", "idle"),
                             Node("demo", "probe", "vital", required=True)))
    assert run_plan(plan, OPTS) == 1
    assert "required process /vital died (exit code 5)" in capsys.readouterr().err


def test_all_required_flag_makes_any_death_fatal(run_env, monkeypatch, capsys):
    monkeypatch.setenv("PROBE_MODE_idle", "sleep")
    monkeypatch.setenv("PROBE_MODE_quitter", "exit3")
    plan = LaunchPlan(nodes=(Node("demo", "probe", "idle"), Node("demo", "probe", "quitter")))
    assert run_plan(plan, dict(OPTS, all_required=True)) == 1
    assert "/quitter" in capsys.readouterr().err


def test_required_node_finishing_cleanly_ends_the_launch_with_zero(run_env, monkeypatch,
                                                                  capsys):
    monkeypatch.setenv("PROBE_MODE_idle", "sleep")
    monkeypatch.setenv("PROBE_MODE_job", "exit0")
    plan = LaunchPlan(nodes=(Node("demo", "probe", "idle"),
                             Node("demo", "probe", "job", required=True)))
    assert run_plan(plan, OPTS) == 0
    assert "required process [/job] has finished" in capsys.readouterr().err


def test_required_node_whose_launch_prefix_cannot_start_exits_nonzero(run_env, monkeypatch,
                                                                      capsys):
    monkeypatch.setenv("PROBE_MODE_idle", "sleep")
    plan = LaunchPlan(nodes=(
        Node("demo", "probe", "idle"),
        Node("demo", "probe", "vital", required=True, launch_prefix="no-such-debugger -x",
             filename="/x/v.launch", line=2)))
    assert run_plan(plan, OPTS) == 1
    err = capsys.readouterr().err
    assert "/x/v.launch:2: cannot start /vital" in err
    assert "required process /vital failed to start" in err


def test_node_timeout_option_overrides_stop_timeouts_per_node(run_env):
    from orchestra.app.options import RunOptions
    from orchestra.supervise.specs import build_specs

    nodes = [Node("demo", "probe", "slow"), Node("demo", "probe", "fast")]
    exes = {n.full_name: run_env["probe"] for n in nodes}
    opts = RunOptions.from_kwargs({"sigint_timeout": 3.0, "node_timeouts": ("/slow=30,5",)})
    slow, fast = build_specs(nodes, exes, "http://m:1/", str(run_env["tmp"]), opts)
    assert (slow.sigint_timeout, slow.sigterm_timeout) == (30.0, 5.0)
    assert (fast.sigint_timeout, fast.sigterm_timeout) == (3.0, 2.0)


@pytest.mark.parametrize("output, flags, expected", [
    (None, {}, OutputMode.LOG), ("screen", {}, OutputMode.SCREEN),
    ("both", {}, OutputMode.BOTH), ("log", {"force_screen": True}, OutputMode.SCREEN),
    ("screen", {"force_log": True}, OutputMode.LOG),
])
def test_output_mode_from_node_and_screen_log_overrides(output, flags, expected):
    from orchestra.app.options import RunOptions
    from orchestra.supervise.specs import output_mode

    assert output_mode(Node("p", "t", "n", output=output), RunOptions(**flags)) == expected


def test_screen_and_log_together_is_a_user_error():
    with pytest.raises(OrchestraError):
        run_plan(LaunchPlan(), {"force_screen": True, "force_log": True})


def test_missing_executable_fails_before_anything_starts(no_master_env):
    from orchestra.master import master_is_up

    run_env = no_master_env
    plan = LaunchPlan(nodes=(Node("demo", "probe", "ok"),
                             Node("demo", "nope", "bad", filename="/x/demo.launch", line=9)))
    with pytest.raises(OrchestraError) as info:
        run_plan(plan, OPTS)
    assert str(info.value).startswith("/x/demo.launch:9: ")
    assert not (run_env["out"] / "ok.json").exists()
    assert not (run_env["tmp"] / "home" / "log").exists()
    assert not master_is_up(f"http://localhost:{run_env['port']}/", timeout=0.5)


def test_remote_machine_with_password_is_refused_unless_local_leaves_it_out(run_env, capsys):
    # (refused before any connection: no traffic to the documentation address 192.0.2.7)
    plan = LaunchPlan(nodes=(Node("demo", "probe", "far", machine_name="robot",
                                  filename="r.launch", line=3),
                             Node("demo", "probe", "near", machine_name="here")),
                      machines={"robot": Machine("robot", address="192.0.2.7", password="pw"),
                                "here": Machine("here", address="localhost")})
    with pytest.raises(OrchestraError) as info:
        run_plan(plan, OPTS)
    assert "r.launch:3: " in str(info.value) and "password" in str(info.value)
    assert not (run_env["out"] / "near.json").exists()
    assert run_plan(plan, dict(OPTS, local=True)) == 0
    assert (run_env["out"] / "near.json").exists()
    assert not (run_env["out"] / "far.json").exists()
    assert "not starting remote node /far" in capsys.readouterr().err


def test_embedded_master_keeps_the_launch_up_after_nodes_end(no_master_env):
    import signal

    returned = threading.Event()
    probe_file = no_master_env["out"] / "probe.json"

    def stop_later() -> None:
        deadline = time.monotonic() + 20
        while not probe_file.exists() and time.monotonic() < deadline:
            time.sleep(0.02)
        # the nodes are done: the launch must not return (waited on, 0.3 s)
        still_running.append(not returned.wait(0.3))
        os.kill(os.getpid(), signal.SIGTERM)

    still_running: list[bool] = []
    thread = threading.Thread(target=stop_later)
    thread.start()
    try:
        code = run_plan(LaunchPlan(params={"/p": 1}, nodes=(Node("demo", "probe", "probe"),)),
                        OPTS)
    finally:
        returned.set()
        thread.join()
    assert code == 0 and still_running == [True]
    assert record(no_master_env, "probe")["param"] == 1


def test_bad_node_timeout_option_is_a_user_error(run_env):
    with pytest.raises(OrchestraError):
        run_plan(LaunchPlan(), dict(OPTS, node_timeouts=("/x=soon",)))


def test_status_socket_reports_every_node(tmp_path):
    import io

    specs = [ProcessSpec(f"/n{i}", ("sleep", "100"), dict(os.environ), str(tmp_path),
                         output=OutputMode.SCREEN) for i in range(3)]
    sup = Supervisor(specs, screen=Screen(io.BytesIO(), io.BytesIO(), colour=False))
    stats = ProcessStats()
    path = str(tmp_path / "s.sock")
    server = StatusServer(sup.loop, lambda: snapshot(sup.procs, stats, {"run_id": "r"}), path)
    answers = []

    def client() -> None:
        deadline = time.monotonic() + 10
        while time.monotonic() < deadline:
            doc = query(path)
            if all(n["state"] == "RUNNING" for n in doc["nodes"]):
                answers.append(doc)
                cli = subprocess.run([sys.executable, "-m", "orchestra", "status",
                                      "--socket", path], capture_output=True, text=True)
                answers.append(cli.stdout)
                break
            time.sleep(0.05)
        sup.loop.call_threadsafe(lambda: sup.request_stop("test done"))

    thread = threading.Thread(target=client)
    thread.start()
    try:
        sup.run(install_signals=False)
    finally:
        thread.join()
        server.close()
    doc, table = answers
    assert doc["run_id"] == "r"
    assert [n["name"] for n in doc["nodes"]] == ["/n0", "/n1", "/n2"]
    assert all(n["pid"] == p.pid for n, p in zip(doc["nodes"], sup.procs, strict=False))
    assert all(isinstance(n["rss"], int) and n["rss"] > 0 for n in doc["nodes"])
    lines = table.splitlines()
    assert lines[1].split()[:2] == ["NODE", "STATE"]
    assert [line.split()[:2] for line in lines[2:]] == [[f"/n{i}", "RUNNING"] for i in range(3)]
    assert not os.path.exists(path)
    assert all(p.state == State.EXITED for p in sup.procs)


def test_orchestra_status_without_launch_says_so(tmp_path):
    env = dict(os.environ, XDG_RUNTIME_DIR=str(tmp_path))
    cli = subprocess.run([sys.executable, "-m", "orchestra", "status"], env=env,
                         capture_output=True, text=True)
    assert cli.returncode == 1 and "no running orchestra launch" in cli.stderr


def test_launch_registers_its_xmlrpc_uri_on_the_master_like_roslaunch(run_env, monkeypatch):
    import signal
    import xmlrpc.client

    monkeypatch.setenv("PROBE_MODE_idle", "sleep")
    master = xmlrpc.client.ServerProxy(os.environ["ROS_MASTER_URI"])
    seen: dict = {}

    def inspect() -> None:
        try:
            deadline = time.monotonic() + 20
            while not (run_env["out"] / "idle.json").exists() and time.monotonic() < deadline:
                time.sleep(0.02)
            code, _, uris = master.getParam("/t", "/roslaunch/uris")
            seen["uris"] = uris
            with xmlrpc.client.ServerProxy(list(uris.values())[0]) as launch:
                seen["pid"] = launch.getPid("/t")[2]
                seen["processes"] = launch.list_processes("/t")[2]
            cli = subprocess.run([sys.executable, "-m", "orchestra", "status", "--master",
                                  "--json"], capture_output=True, text=True)
            seen["cli"] = json.loads(cli.stdout)
        finally:
            os.kill(os.getpid(), signal.SIGTERM)

    thread = threading.Thread(target=inspect)
    thread.start()
    try:
        assert run_plan(LaunchPlan(nodes=(Node("demo", "probe", "idle"),)), OPTS) == 0
    finally:
        thread.join()
    (key, uri), = seen["uris"].items()
    assert key.startswith("host_localhost__") and uri.startswith("http://localhost:")
    assert key.endswith("__" + uri.rsplit(":", 1)[1].rstrip("/"))
    assert seen["pid"] == os.getpid()
    assert seen["processes"] == [["/idle"], []]
    assert [n["name"] for n in seen["cli"][0]["nodes"]] == ["/idle"]
    assert seen["cli"][0]["run_id"] == "testrun"
    # gone from the master when the launch ends (roslaunch leaves stale entries)
    code, _, after = master.getParam("/t", "/roslaunch/uris")
    master("close")()
    assert code != 1 or key not in after


def test_test_nodes_run_only_in_test_mode(run_env):
    from orchestra.launch.plan import Test

    plan = LaunchPlan(nodes=(Node("demo", "probe", "plain"),),
                      tests=(Test("demo", "probe", "checker", test_name="t"),))
    assert run_plan(plan, OPTS) == 0
    assert not (run_env["out"] / "checker.json").exists()
    assert run_plan(plan, dict(OPTS, with_tests=True)) == 0
    assert (run_env["out"] / "checker.json").exists()


def test_two_nodes_with_one_name_are_a_user_error(run_env):
    plan = LaunchPlan(nodes=(Node("demo", "probe", "twin", filename="a.launch", line=1),
                             Node("demo", "probe", "twin", filename="a.launch", line=5)))
    with pytest.raises(OrchestraError) as info:
        run_plan(plan, OPTS)
    assert str(info.value).startswith("a.launch:5: ") and "a.launch:1" in str(info.value)
    assert not (run_env["out"] / "twin.json").exists()


def test_node_path_puts_orchestras_interpreter_first_when_missing():
    from orchestra.supervise.command import path_with_interpreter
    assert path_with_interpreter("/usr/bin:/bin", "/venv/bin/python3") == "/venv/bin:/usr/bin:/bin"
    assert path_with_interpreter("/usr/bin:/venv/bin", "/venv/bin/python3") == "/usr/bin:/venv/bin"
