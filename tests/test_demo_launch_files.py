"""The demo launch files: with default args they resolve exactly like the real ROS files
(compat corpus), and every node of every variant names an executable the package has."""
from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parent.parent
NODE_KEYS = ("package", "type", "name", "namespace", "args", "respawn", "remap_args",
             "env_args", "output", "required")


def env_bundled_only() -> dict:
    env = dict(os.environ)
    for key in ("ROS_PACKAGE_PATH", "CMAKE_PREFIX_PATH", "ROS_NAMESPACE"):
        env.pop(key, None)
    return env


def plan(*words: str) -> dict:
    proc = subprocess.run([sys.executable, "-m", "orchestra", "launch", *words, "--dump-plan"],
                          capture_output=True, text=True, timeout=60, env=env_bundled_only(),
                          cwd=str(REPO))
    assert proc.returncode == 0, proc.stderr
    return json.loads(proc.stdout)


@pytest.mark.parametrize("words, case", [
    (["turtle_tf", "turtle_tf_demo.launch"], "turtle_tf__turtle_tf_demo"),
    (["turtlesim", "multisim.launch"], "turtlesim__multisim"),
])
def test_demo_launch_with_default_args_resolves_like_ros(compat_dir, words, case):
    expected = json.loads((compat_dir / "expected" / f"{case}.json").read_text())
    ours = plan(*words)
    assert ours["params"] == expected["params"]
    assert [{k: n[k] for k in NODE_KEYS} for n in ours["nodes"]] == \
        [{k: n[k] for k in NODE_KEYS} for n in expected["nodes"]]


VARIANTS = [
    ["learning_tf", "start_tf_demo.launch"],
    ["learning_tf", "start_tf_demo.launch", "driver:=auto", "snapshot:=/tmp/x.png"],
    ["learning_tf", "start_tf_demo_py.launch"],
    ["learning_tf", "start_tf_demo_py.launch", "driver:=auto"],
    ["turtle_tf", "turtle_tf_demo.launch", "driver:=auto"],
    ["launch/multi_turtle.launch"],
    ["launch/multi_turtle.launch", "driver:=auto", "snapshot:=/tmp"],
    ["launch/multi_turtle.launch", "driver:=teleop"],
]


@pytest.mark.parametrize("words", VARIANTS, ids=[" ".join(v) for v in VARIANTS])
def test_every_demo_node_has_an_executable_in_its_package(words, monkeypatch):
    from orchestra.packages.executables import find_executable

    for key in ("ROS_PACKAGE_PATH", "CMAKE_PREFIX_PATH"):
        monkeypatch.delenv(key, raising=False)

    nodes = plan(*words)["nodes"]
    assert nodes
    for node in nodes:
        path = find_executable(node["package"], node["type"])
        assert os.access(path, os.X_OK), path


def test_auto_driver_replaces_teleop():
    names = {n["name"] for n in plan("learning_tf", "start_tf_demo.launch", "driver:=auto")["nodes"]}
    assert "driver" in names and "teleop" not in names


def test_demo_executables_are_executable_in_git():
    out = subprocess.run(["git", "ls-files", "-s", "packages/turtlesim/scripts",
                          "packages/tf/scripts", "packages/learning_tf/scripts",
                          "packages/turtle_tf/scripts"], capture_output=True, text=True,
                         cwd=str(REPO), timeout=30).stdout.splitlines()
    assert len(out) >= 13
    for line in out:
        mode, path = line.split()[0], line.split("\t")[1]
        assert mode in ("100755", "120000"), path


@pytest.mark.parametrize("package", ["turtlesim", "tf", "learning_tf", "turtle_tf"])
def test_demo_package_manifest_is_valid_format_2(package):
    from catkin_pkg.package import parse_package

    pkg = parse_package(str(REPO / "packages" / package / "package.xml"))
    pkg.validate()
    assert pkg.package_format == 2 and pkg.name == package
