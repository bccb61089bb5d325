"""The beginner tutorials, unmodified, on orchestra's ROS 1 layer.

tests/ros1_layer/beginner_tutorials is a catkin package written as the ROS tutorials write
it: ``import rospy``, ``from std_msgs.msg import String``, ``from beginner_tutorials.msg
import Person`` (its own msg/), its own srv/AddTwoInts.srv, turtlesim's topics and spawn
service, ``import tf`` for the turtle-follower, params, and an actionlib Fibonacci action
from its own action/. ``orchestra launch beginner_tutorials tutorials.launch`` runs it with
an interpreter that has no ROS at all; every part is observed through orchestra's own
output: the launch's rosout node log (``$ROS_HOME/log/latest/rosout.log``) and an
orchestra.node observer process for the turtles' poses. test_ros1_interop.py runs the same
files under Debian's real rospy against these.
"""
from __future__ import annotations

import json
import math
import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from test_demo_turtles import Observer, free_port

REPO = Path(__file__).resolve().parent.parent
PACKAGES = REPO / "tests" / "ros1_layer"


def layer_env(tmp_path: Path, uri: str) -> dict[str, str]:
    """The user's environment: the tutorial package on the package path, no ROS."""
    env = {k: v for k, v in os.environ.items()
           if k not in ("ROS_PACKAGE_PATH", "CMAKE_PREFIX_PATH", "ROS_NAMESPACE", "DISPLAY")}
    env.update(ROS_PACKAGE_PATH=str(PACKAGES), ROS_MASTER_URI=uri,
               ROS_HOME=str(tmp_path / "ros_home"), PYTHONUNBUFFERED="1")
    return env


class TutorialLaunch:
    """``orchestra launch beginner_tutorials tutorials.launch ...`` with its own master."""

    def __init__(self, tmp_path: Path, *args: str):
        self.uri = f"http://127.0.0.1:{free_port()}/"
        self.env = layer_env(tmp_path, self.uri)
        self.home = tmp_path / "ros_home"
        self.log = open(tmp_path / "launch.log", "w")
        self.started = time.monotonic()
        self.proc = subprocess.Popen(
            [sys.executable, "-m", "orchestra", "launch", "beginner_tutorials",
             "tutorials.launch", *args],
            env=self.env, cwd=str(tmp_path), stdin=subprocess.DEVNULL, stdout=self.log,
            stderr=subprocess.STDOUT, start_new_session=True)

    def output(self) -> str:
        if not self.log.closed:
            self.log.flush()
        return Path(self.log.name).read_text()

    def rosout(self) -> str:
        """Everything the nodes logged, as orchestra's rosout node recorded it."""
        path = self.home / "log" / "latest" / "rosout.log"
        return path.read_text(errors="replace") if path.exists() else ""

    def wait_logged(self, pattern: str, within: float = 30.0) -> re.Match:
        """The first match of ``pattern`` in what the nodes logged: the rosout node's record,
        or the launch's screen output (a line logged before the rosout node had subscribed
        is not on /rosout, with rospy as here, but a node with output="screen" printed it)."""
        deadline = self.started + within
        while True:
            found = re.search(pattern, self.rosout()) or re.search(pattern, self.output())
            if found:
                return found
            assert self.proc.poll() is None, f"launch exited early:\n{self.output()}"
            if time.monotonic() > deadline:
                pytest.fail(f"nothing matched {pattern!r} in {within} s\nrosout.log tail:\n"
                            f"{self.rosout()[-3000:]}\nlaunch output:\n{self.output()[-3000:]}")
            time.sleep(0.1)

    def stop(self) -> int | None:
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGINT)
            try:
                self.proc.wait(20)
            except subprocess.TimeoutExpired:
                os.killpg(self.proc.pid, signal.SIGKILL)
                self.proc.wait()
        self.log.close()
        return self.proc.returncode


@pytest.fixture
def tutorial(tmp_path):
    started: list = []

    def start(*args: str) -> TutorialLaunch:
        launch = TutorialLaunch(tmp_path, *args)
        started.append(launch)
        return launch

    yield start
    for launch in started:
        launch.stop()


def test_no_ros_is_importable_without_the_layer(tmp_path):
    """The premise: the interpreter orchestra runs nodes with has no rospy/genpy of its own."""
    probe = subprocess.run(
        [sys.executable, "-c", "import importlib.util as u; "
         "print([m for m in ('rospy', 'genpy', 'std_msgs', 'tf', 'actionlib') "
         "if u.find_spec(m)])"],
        env=dict(layer_env(tmp_path, "http://127.0.0.1:1/"), PYTHONPATH=str(REPO)),
        capture_output=True, text=True, timeout=30)
    assert probe.stdout.strip() == "[]", probe.stderr


@pytest.mark.timeout(90)
def test_beginner_tutorials_run_unmodified_under_orchestra_launch(tutorial):
    launch = tutorial()
    observer = Observer(launch.env, ["/turtle1/pose", "/turtle2/pose"])
    try:
        # talker -> listener (std_msgs/String, the talker's Publisher made before init_node)
        launch.wait_logged(r"/listener\]? \[.*\]:? /listener I heard hello world \d")
        # the package's own message, published and received
        launch.wait_logged(r"got person Ada aged 36 who likes maths,engines "
                           r"\(beginner_tutorials/Person\)")
        # the package's own service, served and called (by a script that is no node, as in
        # the tutorial: its print() is on the launch's screen output)
        launch.wait_logged(r"\[/add_two_ints_client\] 3 \+ 4 = 7")
        # params: global, relative, private, defaults, set/has/search/delete/list
        seen = json.loads(launch.wait_logged(r"params: (\{.*\})").group(1))
        assert seen == {
            "global": "global value", "relative": 7, "private": "private value",
            "default": "default_value", "gains": {"i": 0.25, "p": 1.0}, "set_here": [1, 2],
            "has_private": True, "has_missing": False, "search": "/global_name",
            "deleted": True, "missing_raises": True, "listed": True, "name": "/params_node",
            "namespace": "/", "resolved": "/params_node/private_name"}
        # actionlib: the Fibonacci server and client of the package's action/
        launch.wait_logged(r"fibonacci result: state 3, sequence 0, 1, 1, 2, 3, 5, 8, 13, 21, "
                           r"34, 55, 9 feedbacks")
        # turtlesim: cmd_vel drives turtle1, its pose comes back to the script
        launch.wait_logged(r"/turtle_circle\]? \[.*\]:? turtle1 at x=\d")
        # tf: turtle2 is spawned by the listener and catches turtle1 through tf lookups
        best = math.inf
        deadline = time.monotonic() + 40
        while time.monotonic() < deadline and best >= 1.0:
            a, b = observer.latest("/turtle1/pose"), observer.latest("/turtle2/pose")
            if a and b:
                best = min(best, math.hypot(a["x"] - b["x"], a["y"] - b["y"]))
            time.sleep(0.05)
        assert best < 1.0, f"turtle2 never caught turtle1 (closest {best:.2f} m)\n" \
                           f"{launch.rosout()[-2000:]}"
        xs = [s["x"] for s in observer.samples["/turtle1/pose"]]
        assert max(xs) - min(xs) > 0.3  # turtle1 really moves
        launch.wait_logged(r"/turtle_tf_listener\]? \[.*\]:? turtle1 is [\d.]+ m from turtle2")
        assert "Traceback" not in launch.output()
    finally:
        observer.stop()
    assert launch.stop() == 0
    assert "Traceback" not in launch.output()
