"""The turtle_tf2 demo (geometry_tutorials' tf2 flavour of the turtle demo): its launch files
resolve like ROS's, every node names an executable of the package, the follower law, and
end to end: ``orchestra launch turtle_tf2 ... driver:=auto`` makes turtle2 catch turtle1
through a tf2 Buffer lookup, then stops cleanly.

The end-to-end tests reuse test_demo_turtles' launch/observer harness (poses are read by a
separate observer process through the topic API)."""
from __future__ import annotations

import json
import math
import os
import subprocess
import sys
import time
from pathlib import Path
from types import SimpleNamespace

import pytest
from test_demo_turtles import BUNDLED_ENV, run_demo, wait_until_close  # noqa: F401 - fixture

REPO = Path(__file__).resolve().parent.parent
PACKAGE = REPO / "packages" / "turtle_tf2"
LAUNCH_FILES = ["turtle_tf2_demo.launch", "turtle_tf2_demo_cpp.launch"]
EXECUTABLES = ["turtle_tf2_broadcaster", "turtle_tf2_broadcaster.py", "turtle_tf2_listener",
               "turtle_tf2_listener.py"]
NODE_KEYS = ("package", "type", "name", "namespace", "args", "respawn", "remap_args",
             "env_args", "output", "required")


def orchestra_launch(*words: str) -> subprocess.CompletedProcess:
    env = {k: v for k, v in BUNDLED_ENV.items() if k != "ROS_NAMESPACE"}
    proc = subprocess.run([sys.executable, "-m", "orchestra", "launch", *words],
                          capture_output=True, text=True, timeout=60, env=env, cwd=str(REPO))
    assert proc.returncode == 0, proc.stderr
    return proc


# --- the launch files ------------------------------------------------------------------------

@pytest.mark.parametrize("launch_file", LAUNCH_FILES)
@pytest.mark.parametrize("driver", [None, "teleop", "auto"])
def test_plan_lists_the_demo_nodes(launch_file, driver):
    words = ["turtle_tf2", launch_file, "--nodes"] + ([f"driver:={driver}"] if driver else [])
    names = orchestra_launch(*words).stdout.split()
    assert names == ["/sim", "/driver" if driver == "auto" else "/teleop",
                     "/turtle1_tf2_broadcaster", "/turtle2_tf2_broadcaster", "/turtle_pointer"]


@pytest.mark.parametrize("launch_file", LAUNCH_FILES)
def test_default_args_resolve_like_ros(compat_dir, launch_file):
    case = f"turtle_tf2__{launch_file[:-len('.launch')]}"
    expected = json.loads((compat_dir / "expected" / f"{case}.json").read_text())
    ours = json.loads(orchestra_launch("turtle_tf2", launch_file, "--dump-plan").stdout)
    assert ours["params"] == expected["params"]
    assert [{k: n[k] for k in NODE_KEYS} for n in ours["nodes"]] == \
        [{k: n[k] for k in NODE_KEYS} for n in expected["nodes"]]


@pytest.mark.parametrize("launch_file", LAUNCH_FILES)
def test_every_node_has_an_executable(launch_file, monkeypatch):
    from orchestra.packages.executables import find_executable

    for key in ("ROS_PACKAGE_PATH", "CMAKE_PREFIX_PATH"):
        monkeypatch.delenv(key, raising=False)
    plan = json.loads(orchestra_launch("turtle_tf2", launch_file, "driver:=auto",
                                       "snapshot:=/tmp/x.png", "--dump-plan").stdout)
    assert len(plan["nodes"]) == 5
    for node in plan["nodes"]:
        assert os.access(find_executable(node["package"], node["type"]), os.X_OK), node


def test_executables_are_executable_in_git():
    out = subprocess.run(["git", "ls-files", "-s", "packages/turtle_tf2/scripts"],
                         capture_output=True, text=True, cwd=str(REPO), timeout=30).stdout
    modes = {line.split("\t")[1].rsplit("/", 1)[1]: line.split()[0]
             for line in out.splitlines()}
    assert sorted(modes) == EXECUTABLES
    assert set(modes.values()) == {"100755"}


def test_manifest_is_valid_format_2():
    from catkin_pkg.package import parse_package

    pkg = parse_package(str(PACKAGE / "package.xml"))
    pkg.validate()
    assert pkg.package_format == 2 and pkg.name == "turtle_tf2"


# --- the nodes' rules ------------------------------------------------------------------------

@pytest.fixture
def core(monkeypatch):
    monkeypatch.syspath_prepend(str(PACKAGE / "src"))
    from turtle_tf2_core import nodes

    return nodes


def test_pose_becomes_world_to_turtle_transform(core):
    from orchestra.node.rostime import Time
    from orchestra.tf import yaw_from_quaternion

    t = core.pose_to_transform(SimpleNamespace(x=3.0, y=4.0, theta=1.0), "turtle1", Time(7))
    assert (t.header.frame_id, t.child_frame_id, t.header.stamp) == ("world", "turtle1", Time(7))
    tr, r = t.transform.translation, t.transform.rotation
    assert (tr.x, tr.y, tr.z) == (3.0, 4.0, 0.0)
    assert math.isclose(yaw_from_quaternion((r.x, r.y, r.z, r.w)), 1.0)


def test_steering_uses_the_tutorials_gains(core):
    from orchestra.tf import tf2_ros

    buffer = tf2_ros.Buffer()
    for turtle, (x, y, theta) in {"turtle1": (5.0, 5.0, 0.0),
                                  "turtle2": (2.0, 1.0, math.pi / 2)}.items():
        pose = SimpleNamespace(x=x, y=y, theta=theta)
        buffer.set_transform(core.pose_to_transform(pose, turtle, 10.0))
    # turtle1 is 3 m ahead on world x and 4 m on world y; turtle2 faces +y: (4, -3) for it
    linear, angular = core.steer(buffer.lookup_transform("turtle2", "turtle1", 0))
    assert math.isclose(linear, 0.5 * 5.0)
    assert math.isclose(angular, 4.0 * math.atan2(-3.0, 4.0))


# --- end to end ------------------------------------------------------------------------------

@pytest.mark.timeout(60)
@pytest.mark.parametrize("launch_file", LAUNCH_FILES)
def test_auto_driver_turtle2_reaches_turtle1_within_15_seconds(run_demo, launch_file):  # noqa: F811
    launch, observer = run_demo(["turtle_tf2", launch_file, "driver:=auto"],
                                ["/turtle1/pose", "/turtle2/pose"])
    wait_until_close(launch, observer, "/turtle1/pose", "/turtle2/pose", within=15.0)
    # turtle2 really moved (the observer may join after it left its spawn point at (4, 2),
    # so count the path it was seen to travel); turtle1 really is driven
    def travelled() -> float:
        path = list(observer.samples["/turtle2/pose"])
        return sum(math.hypot(b["x"] - a["x"], b["y"] - a["y"]) for a, b in zip(path, path[1:], strict=False))

    def x_range() -> float:
        xs = [s["x"] for s in list(observer.samples["/turtle1/pose"])]
        return max(xs) - min(xs)

    deadline = time.monotonic() + 15
    while (travelled() <= 0.5 or x_range() <= 1.0) and time.monotonic() < deadline:
        time.sleep(0.1)
    assert travelled() > 0.5 and x_range() > 1.0
    assert launch.stop() == 0
