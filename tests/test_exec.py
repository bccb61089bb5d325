"""The argv / env / cwd a node is exec'd with, pinned against what roslaunch builds.

The plans are hand-built from ../shared/compat/argv/ws so these tests do not depend on the
launch interpreter; the end-to-end check is ``compare.py --set argv``.
"""
from __future__ import annotations

import json
import os

import pytest

from orchestra.launch.plan import LaunchPlan, Node
from orchestra.supervise.command import (
    BadNodeCommand,
    ExecutableNotFound,
    exec_table,
    node_argv,
    node_cwd,
    node_env,
)


@pytest.fixture
def argv_ws(compat_dir, monkeypatch):
    ws = compat_dir / "argv" / "ws"
    monkeypatch.setenv("ROS_PACKAGE_PATH", str(ws))
    monkeypatch.delenv("CMAKE_PREFIX_PATH", raising=False)
    return ws


def _expected(compat_dir, name, ws):
    text = (compat_dir / "argv" / "expected" / name).read_text().replace("${WS}", str(ws))
    return json.loads(text)["exec"]


def _argv_launch_plan(ws) -> LaunchPlan:
    """argv.launch as roslaunch resolves it (anon name fixed)."""
    top = (("TOP_ENV", "top"),)
    return LaunchPlan(nodes=(
        Node("argv_demo", "talker", "talker", "/", args="--rate 10 'quoted arg' -v",
             remap_args=(("chatter", "/global_chatter"), ("out", "talker_out")), env_args=top),
        Node("argv_demo", "listener", "listener", "/robot1/", cwd="node", output="screen",
             remap_args=(("chatter", "/global_chatter"), ("input", "sensors/input")),
             env_args=top + (("GROUP_ENV", "g1"), ("NODE_ENV", "n1"))),
        Node("argv_demo", "relay", "relay", "/robot1/arm/", launch_prefix="nice -n 5",
             respawn=True, respawn_delay=2.0,
             remap_args=(("chatter", "/global_chatter"), ("input", "sensors/input"),
                         ("~private_in", "/abs_in")),
             env_args=top + (("GROUP_ENV", "g1"),)),
        Node("argv_demo", "talker", "talker_ANON", "/abs_ns/",
             args=f"{ws}/argv_demo/launch", remap_args=(("chatter", "/global_chatter"),),
             env_args=top),
    ))


def test_exec_table_matches_roslaunch_argv_and_env_additions(compat_dir, argv_ws):
    assert exec_table(_argv_launch_plan(argv_ws)) == _expected(compat_dir, "argv.json", argv_ws)


def test_exec_table_include_ns_quoting_and_scripts_dir(compat_dir, argv_ws):
    plan = LaunchPlan(nodes=(
        Node("argv_demo", "py_node.py", "turtle1_py", "/left/", args='--speed=2 "two words"',
             remap_args=(("cmd", "turtle1/cmd_vel"),), env_args=(("INC_ENV", "inc"),)),
        Node("argv_demo", "tool", "tool_turtle1", "/left/tools/",
             remap_args=(("cmd", "top_cmd"),), env_args=(("INC_ENV", "inc"),)),
        Node("argv_demo", "py_node.py", "turtle2_py", "/right/",
             remap_args=(("cmd", "turtle2/cmd_vel"),)),
        Node("argv_demo", "tool", "tool_turtle2", "/right/tools/",
             remap_args=(("cmd", "right_cmd"),)),
        Node("argv_demo", "listener", "lone", "/", args="a b", machine_name="here",
             remap_args=(("cmd", "top_cmd"), ("a", "c"))),
    ))
    assert exec_table(plan) == _expected(compat_dir, "include_ns.json", argv_ws)


def test_node_argv_appends_log_file_last():
    node = Node("p", "t", "n", "/ns/", args="x")
    argv = node_argv(node, executable="/bin/t", log_file="/logs/ns-n-1.log")
    assert argv == ["/bin/t", "x", "__name:=n", "__log:=/logs/ns-n-1.log"]


def test_node_env_master_uri_and_env_tags_override_namespace():
    node = Node("p", "t", "n", "/a/b/", env_args=(("ROS_NAMESPACE", "/forced"), ("X", "1")))
    env = node_env(node, master_uri="http://localhost:1234/")
    assert env == {"ROS_MASTER_URI": "http://localhost:1234/", "ROS_NAMESPACE": "/forced",
                   "X": "1"}
    assert "ROS_NAMESPACE" not in node_env(Node("p", "t", "n", "/"))


def test_node_cwd_node_is_executable_dir_even_with_launch_prefix(tmp_path):
    node = Node("p", "t", "n", cwd="node", launch_prefix="nice -n 5")
    assert node_cwd(node, "/opt/pkg/bin/t") == "/opt/pkg/bin"


def test_node_cwd_defaults_to_ros_home(tmp_path):
    env = {"ROS_HOME": str(tmp_path / "home")}
    assert node_cwd(Node("p", "t", "n"), "/x/t", env) == str(tmp_path / "home")
    assert node_cwd(Node("p", "t", "n", cwd="cwd"), "/x/t", env) == os.getcwd()


def test_missing_executable_names_launch_file_line(argv_ws):
    node = Node("argv_demo", "nope", "n", filename="/x/a.launch", line=7)
    with pytest.raises(ExecutableNotFound) as info:
        node_argv(node)
    assert str(info.value).startswith("/x/a.launch:7: ")
    assert "nope" in str(info.value)


def test_non_executable_file_is_not_an_executable(tmp_path, monkeypatch):
    pkg = tmp_path / "pkg"
    (pkg / "scripts").mkdir(parents=True)
    (pkg / "package.xml").write_text("<package><name>pkg</name></package>")
    (pkg / "scripts" / "plain").write_text("#!/bin/sh\n")
    monkeypatch.setenv("ROS_PACKAGE_PATH", str(tmp_path))
    with pytest.raises(ExecutableNotFound):
        node_argv(Node("pkg", "plain", "n"))


def test_exec_table_keeps_entry_for_missing_executable(argv_ws):
    table = exec_table(LaunchPlan(nodes=(Node("argv_demo", "nope", "n"),)))
    assert table["/n"]["argv"] == ["nope", "__name:=n"]
    assert "nope" in table["/n"]["error"]


def test_unbalanced_quote_in_args_is_a_user_error():
    with pytest.raises(BadNodeCommand) as info:
        node_argv(Node("p", "t", "n", args="'open", filename="f.launch", line=3),
                  executable="/bin/t")
    assert str(info.value).startswith("f.launch:3: ")
