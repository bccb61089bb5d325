"""``<rosparam command="dump">`` / ``command="delete"``: recorded in the plan, run at launch.

roslaunch runs them as ``rosparam`` commands in its setup phase: after the master is up and
BEFORE clear_params and the parameter upload, in document order. The run-time tests use a
master of their own on a free port and launch files without nodes, so each run returns at
once.
"""
from __future__ import annotations

import os
import subprocess
import sys
import textwrap
import xmlrpc.client
from pathlib import Path

import pytest

from orchestra.app.cli import options_from_cli, serve_plan
from orchestra.errors import OrchestraError
from orchestra.launch.interpreter import Interpreter, LoadOptions, load_launch
from orchestra.launch.plan import ParamAction
from orchestra.params.dump import dump_yaml

pytestmark = pytest.mark.timeout(60)


def run_plan(plan, options):
    """What ``orchestra launch`` does with a plan and its flags (click's keyword arguments)."""
    return serve_plan(plan, options_from_cli(options))


OPTS = {"run_id": "rosparam-actions", "status_view": False, "disable_title": True}


def write(tmp_path: Path, body: str, name: str = "t.launch") -> Path:
    path = tmp_path / name
    path.write_text(f"<launch>\n{textwrap.dedent(body)}</launch>\n")
    return path


# ------------------------------------------------------------------ the plan

def test_dump_and_delete_are_recorded_in_document_order_with_full_names(tmp_path):
    path = write(tmp_path, """\
        <arg name="out" default="all.yaml"/>
        <rosparam command="dump" file="$(arg out)"/>
        <group ns="g">
          <rosparam command="delete" param="old"/>
          <rosparam command="delete" ns="sub" param="p"/>
          <rosparam command="delete" param="skipped" if="false"/>
          <rosparam command="dump" file="g.yaml"/>
          <node pkg="demo" type="t" name="n">
            <rosparam command="delete" param="stale"/>
            <rosparam command="dump" file="n.yaml" unless="0"/>
          </node>
        </group>
        <rosparam command="delete" param="/abs/name"/>
        """)
    plan = load_launch(str(path))
    got = [(a.command, a.param, a.file, a.line) for a in plan.param_actions]
    assert got == [
        ("dump", "/", "all.yaml", 3),
        ("delete", "/g/old", None, 5),
        ("delete", "/g/sub/p", None, 6),
        ("dump", "/g", "g.yaml", 8),
        ("delete", "/g/n/stale", None, 10),
        ("dump", "/g/n", "n.yaml", 11),
        ("delete", "/abs/name", None, 14),
    ]
    assert {a.filename for a in plan.param_actions} == {str(path)}
    assert plan.params == {}  # recorded as actions, never as parameters


def test_actions_in_an_included_file_name_that_file_and_the_include_namespace(tmp_path):
    inner = write(tmp_path, '<rosparam command="delete" param="x"/>\n', "inner.launch")
    outer = write(tmp_path, f'<include file="{inner}" ns="robot"/>\n')
    (action,) = load_launch(str(outer)).param_actions
    assert action == ParamAction("delete", "/robot/x", None, str(inner), 2)


def test_dump_plan_json_adds_param_actions_and_keeps_the_compat_keys(tmp_path):
    path = write(tmp_path, '<group ns="g"><rosparam command="dump" file="f.yaml"/></group>\n')
    doc = load_launch(str(path)).to_json()
    assert list(doc)[:6] == ["params", "clear_params", "nodes", "tests", "machines",
                             "files_loaded"]
    assert doc["param_actions"] == [{"command": "dump", "param": "/g", "file": "f.yaml",
                                     "filename": str(path), "line": 2}]


def test_private_name_resolves_under_rosparam_like_the_rosparam_tool_with_a_warning(tmp_path):
    path = write(tmp_path, '<rosparam command="delete" param="~secret"/>\n')
    interp = Interpreter(LoadOptions())
    interp.load_file(str(path))
    assert [a.param for a in interp.plan().param_actions] == ["/rosparam/secret"]
    assert any("/rosparam/secret" in w for w in interp.warnings)


# ------------------------------------------------------------------ at launch time

@pytest.fixture
def master(tmp_path, monkeypatch):
    """A master of our own on a free port at ROS_MASTER_URI; the launch runs in tmp_path."""
    from orchestra.master import start_master

    handle = start_master("127.0.0.1", 0)
    for key in ("ROS_LOG_DIR", "ROS_NAMESPACE"):
        monkeypatch.delenv(key, raising=False)
    monkeypatch.setenv("ROS_MASTER_URI", handle.uri)
    monkeypatch.setenv("ROS_HOME", str(tmp_path / "home"))
    monkeypatch.setenv("XDG_RUNTIME_DIR", str(tmp_path))
    monkeypatch.chdir(tmp_path)
    yield handle
    handle.shutdown()


def server_params(handle) -> dict:
    with xmlrpc.client.ServerProxy(handle.uri) as master:
        code, _, value = master.getParam("/test", "/")
    assert code == 1
    return value


def test_delete_in_group_ns_removes_a_param_left_on_the_running_master(master, tmp_path):
    master.params.set("/g/old", 5)
    master.params.set("/g/other", 6)
    path = write(tmp_path, """\
        <group ns="g">
          <rosparam command="delete" param="old"/>
        </group>
        """)
    assert run_plan(load_launch(str(path)), OPTS) == 0
    assert server_params(master)["g"] == {"other": 6}


def test_delete_runs_before_the_upload_so_this_launchs_own_param_is_set(master, tmp_path):
    master.params.set("/g/p", "left over")
    path = write(tmp_path, """\
        <group ns="g">
          <param name="p" value="fresh"/>
          <rosparam command="delete" param="p"/>
        </group>
        """)
    assert run_plan(load_launch(str(path)), OPTS) == 0
    assert server_params(master)["g"] == {"p": "fresh"}


def test_delete_clears_stale_dict_keys_before_a_rosparam_load(master, tmp_path):
    # the pattern roslaunch's order exists for: a reload does not merge with an old run's keys
    master.params.set("/g/cfg", {"a": 1, "gone": 2})
    path = write(tmp_path, """\
        <group ns="g">
          <rosparam command="delete" param="cfg"/>
          <rosparam param="cfg">{a: 10, b: 20}</rosparam>
        </group>
        """)
    assert run_plan(load_launch(str(path)), OPTS) == 0
    assert server_params(master)["g"] == {"cfg": {"a": 10, "b": 20}}


def test_delete_of_a_missing_param_warns_with_file_line_and_the_launch_goes_on(
        master, tmp_path, capsys):
    path = write(tmp_path, """\
        <rosparam command="delete" param="nothing/here"/>
        <param name="after" value="1"/>
        """)
    assert run_plan(load_launch(str(path)), OPTS) == 0
    err = capsys.readouterr().err
    assert f"{path}:2: rosparam delete: parameter [/nothing/here] is not set" in err
    assert server_params(master)["after"] == 1


def test_delete_of_the_root_empties_the_server_before_the_upload(master, tmp_path):
    master.params.set("/old/a", 1)
    path = write(tmp_path, """\
        <rosparam command="delete"/>
        <param name="new" value="2"/>
        """)
    assert run_plan(load_launch(str(path)), OPTS) == 0
    params = server_params(master)
    assert "old" not in params and params["new"] == 2


def test_dump_in_group_ns_writes_rosparam_yaml_of_the_server_before_this_launch(
        master, tmp_path):
    master.params.set("/g/a", 1)
    master.params.set("/g/sub", {"b": "two", "c": [1.5, True]})
    master.params.set("/elsewhere", 3)
    path = write(tmp_path, """\
        <group ns="g">
          <param name="mine" value="not yet"/>
          <rosparam command="dump" file="g.yaml"/>
        </group>
        """)
    assert run_plan(load_launch(str(path)), OPTS) == 0
    text = (tmp_path / "g.yaml").read_text()
    assert text == "a: 1\nsub:\n  b: two\n  c:\n  - 1.5\n  - true\n"
    assert text == dump_yaml({"a": 1, "sub": {"b": "two", "c": [1.5, True]}})
    assert server_params(master)["g"]["mine"] == "not yet"  # uploaded after the dump


def test_dump_sees_the_params_an_earlier_launch_uploaded(master, tmp_path, capsys):
    path = write(tmp_path, """\
        <group ns="robot">
          <rosparam command="dump" file="robot.yaml"/>
          <param name="speed" value="0.5"/>
          <rosparam>{limits: {max: 3}}</rosparam>
        </group>
        """)
    plan = load_launch(str(path))
    assert run_plan(plan, OPTS) == 0  # first run: nothing under /robot yet
    assert not (tmp_path / "robot.yaml").exists()
    err = capsys.readouterr().err
    assert f"{path}:3: rosparam dump: " in err and "[/robot] is not set" in err.lower()
    assert run_plan(plan, OPTS) == 0  # second run: the first run's upload
    assert (tmp_path / "robot.yaml").read_text() == "limits:\n  max: 3\nspeed: 0.5\n"


def test_dump_runs_before_clear_params(master, tmp_path):
    master.params.set("/g/old", "still there")
    path = write(tmp_path, """\
        <group ns="g" clear_params="true">
          <rosparam command="dump" file="before_clear.yaml"/>
        </group>
        """)
    assert run_plan(load_launch(str(path)), OPTS) == 0
    assert (tmp_path / "before_clear.yaml").read_text() == "old: still there\n"
    assert "g" not in server_params(master)


def test_actions_run_in_document_order(master, tmp_path):
    master.params.set("/g/a", 1)
    master.params.set("/g/b", 2)
    path = write(tmp_path, """\
        <rosparam command="dump" ns="g" file="first.yaml"/>
        <rosparam command="delete" param="g/a"/>
        <rosparam command="dump" param="g" file="second.yaml"/>
        """)
    assert run_plan(load_launch(str(path)), OPTS) == 0
    assert (tmp_path / "first.yaml").read_text() == "a: 1\nb: 2\n"
    assert (tmp_path / "second.yaml").read_text() == "b: 2\n"


@pytest.mark.parametrize("body, message", [
    ('<rosparam command="dump"/>', "'file' must be set"),
    ('<rosparam command="dump" file="no/such/dir/out.yaml"/>', "no directory"),
])
def test_a_dump_that_cannot_write_is_refused_before_the_master_is_touched(
        master, tmp_path, body, message):
    master.params.set("/keep", 1)
    path = write(tmp_path, f'<rosparam command="delete" param="keep"/>\n{body}\n')
    with pytest.raises(OrchestraError) as info:
        run_plan(load_launch(str(path)), OPTS)
    assert message in info.value.message
    assert (info.value.location.file, info.value.location.line) == (str(path), 3)
    assert server_params(master) == {"keep": 1}  # not even the delete before it ran


def test_orchestra_launch_runs_the_actions_against_ros_master_uri(master, tmp_path):
    master.params.set("/ns1/stale", True)
    master.params.set("/ns1/keep", "k")
    path = write(tmp_path, """\
        <group ns="ns1">
          <rosparam command="delete" param="stale"/>
          <rosparam command="dump" file="$(dirname)/ns1.yaml"/>
        </group>
        """)
    env = dict(os.environ)
    proc = subprocess.run([sys.executable, "-m", "orchestra", "launch", str(path),
                           "--disable-title", "--run-id", "rosparam-actions-cli"],
                          env=env, capture_output=True, text=True, timeout=60)
    assert proc.returncode == 0, proc.stderr
    assert (tmp_path / "ns1.yaml").read_text() == "keep: k\n"
    assert "stale" not in server_params(master)["ns1"]


def test_orchestra_launch_refuses_a_dump_without_file_with_file_line_exit_2(tmp_path):
    path = write(tmp_path, '<group ns="g"><rosparam command="dump"/></group>\n')
    env = dict(os.environ, ROS_MASTER_URI="http://127.0.0.1:9/")  # nobody: never reached
    proc = subprocess.run([sys.executable, "-m", "orchestra", "launch", str(path)],
                          env=env, capture_output=True, text=True, timeout=60)
    assert proc.returncode == 2
    assert f"orchestra: error: {path}:2:" in proc.stderr
    assert "'file' must be set" in proc.stderr and "Traceback" not in proc.stderr
