"""The beginner tutorials' SAME files under Debian's real ROS 1 and under orchestra's layer,
talking to each other in both directions.

tests/ros1_layer/beginner_tutorials runs unchanged under /usr/bin/python3 with real rospy,
tf and actionlib; its own msg/srv/action types are generated for real ROS here with Debian's
genpy/genmsg/genaction scripts (what catkin_make would do), the layer needs no build step.
Each pair crosses the boundary both ways on one orchestra master: talker -> listener,
Person publisher -> listener, AddTwoInts server <- client, Fibonacci action server <- client,
and the tf tutorial's broadcaster -> listener around the bundled turtlesim. Skipped, with the
reason, where Debian's ROS 1 or its generators are not installed.
"""
from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest
from test_ros1_tutorials import PACKAGES

sys.path.insert(0, str(Path(__file__).resolve().parent / "node_fixtures"))
import harness  # noqa: E402

ROS_PYTHON = harness.ROS_PYTHON
GENMSG = "/usr/lib/genpy/genmsg_py.py"
GENSRV = "/usr/lib/genpy/gensrv_py.py"
GENACTION = "/usr/lib/actionlib_msgs/genaction.py"
SHARE = Path("/usr/share")
TUTORIALS = PACKAGES / "beginner_tutorials"
TURTLESIM = Path(__file__).resolve().parent.parent / "packages" / "turtlesim"


def _require_real_ros() -> None:
    missing = [p for p in (ROS_PYTHON, GENMSG, GENSRV, GENACTION,
                           str(SHARE / "std_msgs" / "msg"), str(SHARE / "actionlib_msgs" / "msg"))
               if not os.path.exists(p)]
    if missing:
        pytest.skip(f"Debian's ROS 1 generators/definitions are not installed: {missing}")
    probe = subprocess.run([ROS_PYTHON, "-c", "import rospy, tf, actionlib, genpy"],
                           capture_output=True, text=True, timeout=60,
                           env={k: v for k, v in os.environ.items() if k != "PYTHONPATH"})
    if probe.returncode != 0:
        pytest.skip(f"Debian's rospy/tf/actionlib are not importable: {probe.stderr[-200:]}")


def _run(argv: list[str]) -> None:
    proc = subprocess.run([ROS_PYTHON, *argv], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, f"{argv}: {proc.stderr}"


def generate(pkg: str, src: Path, out: Path, work: Path) -> None:
    """``out/<pkg>/{msg,srv}``: genpy's Python for ``src``'s msg/, srv/ and action/."""
    includes = [f"-I{pkg}:{src / 'msg'}"]
    for dep in ("std_msgs", "actionlib_msgs", "geometry_msgs"):
        includes.append(f"-I{dep}:{SHARE / dep / 'msg'}")
    msgs = sorted((src / "msg").glob("*.msg")) if (src / "msg").is_dir() else []
    actions = sorted((src / "action").glob("*.action")) if (src / "action").is_dir() else []
    if actions:
        generated = work / f"{pkg}_action"
        _run([GENACTION, "-o", str(generated), *map(str, actions)])
        includes.append(f"-I{pkg}:{generated}")
        msgs += sorted(generated.glob("*.msg"))
    (out / pkg).mkdir(parents=True, exist_ok=True)
    (out / pkg / "__init__.py").write_text("")
    if msgs:
        _run([GENMSG, "-p", pkg, *includes, "-o", str(out / pkg / "msg"), *map(str, msgs)])
        _run([GENMSG, "--initpy", "-p", pkg, "-o", str(out / pkg / "msg")])
    srvs = sorted((src / "srv").glob("*.srv")) if (src / "srv").is_dir() else []
    if srvs:
        _run([GENSRV, "-p", pkg, *includes, "-o", str(out / pkg / "srv"), *map(str, srvs)])
        _run([GENSRV, "--initpy", "-p", pkg, "-o", str(out / pkg / "srv")])


@pytest.fixture(scope="module")
def generated(tmp_path_factory) -> Path:
    _require_real_ros()
    out = tmp_path_factory.mktemp("genpy")
    generate("beginner_tutorials", TUTORIALS, out, out)
    generate("turtlesim", TURTLESIM, out, out)
    return out


class Mixed(harness.ProcessGroup):
    """Tutorial scripts against one master, each under real rospy or under the layer."""

    def __init__(self, master_uri: str, generated: Path):
        super().__init__(master_uri)
        base = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "ROS_NAMESPACE")}
        base.update(ROS_MASTER_URI=master_uri, PYTHONUNBUFFERED="1")
        self.ros_env = dict(base, PYTHONPATH=str(generated))
        # the layer as orchestra gives it to a node (orchestra/ros1/activation.py)
        from orchestra.ros1.activation import layer_env

        self.layer_env = dict(base, ROS_PACKAGE_PATH=str(PACKAGES),
                              PYTHONPATH=os.environ.get("PYTHONPATH", ""))
        self.layer_env.update(layer_env(self.layer_env))

    def real(self, script: str, *args: str) -> harness.NodeProcess:
        return self._start([ROS_PYTHON, str(TUTORIALS / "scripts" / script), *args],
                           self.ros_env)

    def layer(self, script: str, *args: str) -> harness.NodeProcess:
        return self._start([sys.executable, str(TUTORIALS / "scripts" / script), *args],
                           self.layer_env)


@pytest.fixture
def mixed(master, generated):
    group = Mixed(master.uri, generated)
    yield group
    group.close()


def heard(node: harness.NodeProcess, text: str, timeout: float = 30.0) -> str:
    return node.expect(lambda d: text in d.get("text", ""), timeout)["text"]


def test_real_rospy_uses_genpy_and_the_layer_does_not(mixed):
    """The two sides really are different implementations."""
    code = "import rospy, std_msgs.msg as m; print(rospy.__file__, type(m.String).__module__)"
    real = subprocess.run([ROS_PYTHON, "-c", code], env=mixed.ros_env, capture_output=True,
                          text=True, timeout=60)
    ours = subprocess.run([sys.executable, "-c", code], env=mixed.layer_env,
                          capture_output=True, text=True, timeout=60)
    assert "/usr/lib/python3/dist-packages/rospy" in real.stdout, real.stderr
    assert "orchestra/ros1/site/rospy" in ours.stdout, ours.stderr


@pytest.mark.timeout(120)
def test_topics_cross_both_ways_std_msgs_and_the_packages_own_person(mixed):
    to_layer = ["chatter:=/to_layer", "people:=/people_to_layer"]
    to_real = ["chatter:=/to_real", "people:=/people_to_real"]
    listeners = [
        mixed.layer("listener.py", "__name:=layer_listener", *to_layer),
        mixed.real("listener.py", "__name:=real_listener", *to_real),
        mixed.layer("person_listener.py", "__name:=layer_person_listener", *to_layer),
        mixed.real("person_listener.py", "__name:=real_person_listener", *to_real),
    ]
    mixed.real("talker.py", "__name:=real_talker", *to_layer)
    mixed.layer("talker.py", "__name:=layer_talker", *to_real)
    mixed.real("person_publisher.py", "__name:=real_person_publisher", "_name:=Real",
               *to_layer)
    mixed.layer("person_publisher.py", "__name:=layer_person_publisher", "_name:=Layer",
                *to_real)
    assert "/layer_listener I heard hello world" in heard(listeners[0], "I heard")
    assert "/real_listener I heard hello world" in heard(listeners[1], "I heard")
    assert "got person Real aged 36 who likes maths,engines (beginner_tutorials/Person)" \
        in heard(listeners[2], "got person")
    assert "got person Layer aged 36 who likes maths,engines (beginner_tutorials/Person)" \
        in heard(listeners[3], "got person")


@pytest.mark.timeout(120)
def test_services_and_actions_cross_both_ways(mixed):
    # the tutorial's client is no node: real rospy ignores remappings there (they apply from
    # init_node on; orchestra applies them, docs/compat.md), so the real client finds the
    # layer's server under the tutorial's own name
    mixed.real("add_two_ints_server.py", "__name:=real_adder", "add_two_ints:=/real_adds")
    mixed.layer("add_two_ints_server.py", "__name:=layer_adder")
    mixed.real("fibonacci_server.py", "__name:=real_fibonacci")
    mixed.layer("fibonacci_server.py", "__name:=layer_fibonacci")
    clients = [
        mixed.layer("add_two_ints_client.py", "3", "4", "add_two_ints:=/real_adds"),
        mixed.real("add_two_ints_client.py", "5", "6"),
        mixed.layer("fibonacci_client.py", "__name:=layer_fib_client", "_server:=/real_fibonacci",
                    "_order:=6"),
        mixed.real("fibonacci_client.py", "__name:=real_fib_client", "_server:=/layer_fibonacci",
                   "_order:=7"),
    ]
    assert "3 + 4 = 7" in heard(clients[0], " = ")
    assert "5 + 6 = 11" in heard(clients[1], " = ")
    assert "fibonacci result: state 3, sequence 0, 1, 1, 2, 3, 5, 8, 5 feedbacks" \
        in heard(clients[2], "fibonacci result")
    assert "fibonacci result: state 3, sequence 0, 1, 1, 2, 3, 5, 8, 13, 6 feedbacks" \
        in heard(clients[3], "fibonacci result")
    for client in clients:
        assert client.wait(20) == 0


@pytest.mark.timeout(120)
def test_tf_tutorial_real_broadcasters_drive_the_layers_listener_and_back(mixed):
    """turtle1's frame from a real tf broadcaster, turtle2's from the layer's; the layer's
    listener spawns turtle2 and steers it, then the same with a real listener."""
    mixed._start([sys.executable, "-m", "orchestra", "run", "turtlesim", "turtlesim_node",
                  "__name:=sim"], mixed.layer_env)
    mixed.layer("turtle_circle.py", "_speed:=0.6")
    mixed.real("turtle_tf_broadcaster.py", "__name:=b1", "_turtle:=turtle1")
    mixed.layer("turtle_tf_broadcaster.py", "__name:=b2", "_turtle:=turtle2")
    follower = mixed.layer("turtle_tf_listener.py", "__name:=layer_follower")
    line = heard(follower, "m from turtle2", timeout=40)
    assert "turtle1 is" in line
    # and a real tf listener reads the same tree (one frame from each side)
    real_tf = mixed._start([ROS_PYTHON, "-c", (
        "import rospy, tf\n"
        "rospy.init_node('real_tf_reader')\n"
        "l = tf.TransformListener()\n"
        "l.waitForTransform('/turtle2', '/turtle1', rospy.Time(0), rospy.Duration(20))\n"
        "(t, r) = l.lookupTransform('/turtle2', '/turtle1', rospy.Time(0))\n"
        "print('real tf sees turtle1 from turtle2 at %.2f m' % (t[0] ** 2 + t[1] ** 2) ** 0.5)\n")],
        mixed.ros_env)
    assert "real tf sees turtle1 from turtle2" in heard(real_tf, "real tf sees")
