"""End-to-end turtle demos: ``orchestra launch`` runs them headless on a free port and a
separate observer process reads the turtles' poses through the topic API.

The observer is this file run as a script (``python test_demo_turtles.py observe TOPIC...``):
a node runtime is one per process and bound to one master, so each launch gets a fresh
observer instead of sharing the pytest process with other tests' masters.
"""
from __future__ import annotations

import itertools
import json
import math
import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent / "node_fixtures"))
from harness import free_port  # noqa: E402

# orchestra's bundled packages, whatever ROS workspace the developer's shell points at
BUNDLED_ENV = {k: v for k, v in os.environ.items()
               if k not in ("ROS_PACKAGE_PATH", "CMAKE_PREFIX_PATH")}

REPO = Path(__file__).resolve().parent.parent
PEN = (179, 184, 255)
PX_PER_METER = 45.0
WORLD = (500 - 1) / PX_PER_METER


class Observer:
    """Latest pose per topic, and every sample, from an observer subprocess."""

    def __init__(self, env: dict, topics: list[str]):
        self.samples: dict[str, list[dict]] = {t: [] for t in topics}
        self.proc = subprocess.Popen([sys.executable, __file__, "observe", *topics], env=env,
                                     stdout=subprocess.PIPE, stderr=subprocess.DEVNULL,
                                     stdin=subprocess.DEVNULL, text=True)
        self.reader = threading.Thread(target=self._read, daemon=True)
        self.reader.start()

    def _read(self) -> None:
        for line in self.proc.stdout:
            try:
                sample = json.loads(line)
            except ValueError:
                continue
            if "topic" in sample:
                self.samples[sample["topic"]].append(sample)

    def latest(self, topic: str) -> dict | None:
        s = self.samples[topic]
        return s[-1] if s else None

    def stop(self) -> None:
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGINT)
            try:
                self.proc.wait(10)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
        self.reader.join(10)         # it reads up to the end of the pipe, then we close it
        if not self.reader.is_alive():
            self.proc.stdout.close()


class Launch:
    """``orchestra launch ...`` as a subprocess with its own embedded master on a free port."""

    def __init__(self, tmp_path: Path, *words: str):
        self.uri = f"http://127.0.0.1:{free_port()}/"
        self.env = dict(BUNDLED_ENV, ROS_MASTER_URI=self.uri, ROS_HOME=str(tmp_path / "ros_home"),
                        PYTHONUNBUFFERED="1")
        self.env.pop("DISPLAY", None)  # headless whatever the developer's session has
        self.env.pop("ROS_NAMESPACE", None)
        self.log = open(tmp_path / "launch.log", "w")
        self.started = time.monotonic()
        self.proc = subprocess.Popen([sys.executable, "-m", "orchestra", "launch", *words],
                                     env=self.env, cwd=str(tmp_path), stdin=subprocess.DEVNULL,
                                     stdout=self.log, stderr=subprocess.STDOUT,
                                     start_new_session=True)

    def elapsed(self) -> float:
        return time.monotonic() - self.started

    def stop(self) -> int | None:
        """SIGINT like Ctrl-C; the process group is killed only if that did not work."""
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGINT)
            try:
                self.proc.wait(20)
            except subprocess.TimeoutExpired:
                os.killpg(self.proc.pid, signal.SIGKILL)
                self.proc.wait()
        self.log.close()
        return self.proc.returncode

    def output(self) -> str:
        self.log.flush()
        return Path(self.log.name).read_text()


@pytest.fixture
def run_demo(tmp_path):
    """Start a launch plus an observer; both are stopped at the end of the test."""
    running: list = []

    def start(words: list[str], topics: list[str]) -> tuple[Launch, Observer]:
        launch = Launch(tmp_path, *words)
        observer = Observer(launch.env, topics)
        running.append((launch, observer))
        return launch, observer

    yield start
    for launch, observer in running:
        observer.stop()
        launch.stop()


def distance(a: dict, b: dict) -> float:
    return math.hypot(a["x"] - b["x"], a["y"] - b["y"])


def wait_until_close(launch: Launch, observer: Observer, a: str, b: str, within: float,
                     limit: float = 1.0) -> float:
    """Seconds since launch when the two turtles were first closer than ``limit`` metres."""
    best = math.inf
    while launch.elapsed() < within:
        pa, pb = observer.latest(a), observer.latest(b)
        if pa and pb:
            best = min(best, distance(pa, pb))
            if best < limit:
                return launch.elapsed()
        assert launch.proc.poll() is None, f"launch exited early:\n{launch.output()}"
        time.sleep(0.05)
    pytest.fail(f"turtles never got within {limit} m in {within} s (closest {best:.2f} m)\n"
                f"{launch.output()}")


def travelled(samples: list[dict]) -> float:
    """Length in metres of the path through a topic's pose samples."""
    return sum(math.dist((a["x"], a["y"]), (b["x"], b["y"])) for a, b in itertools.pairwise(samples))


def wait_until_travelled(launch: Launch, observer: Observer, topics: tuple[str, ...],
                         metres: float, within: float) -> None:
    """Wait until every topic's turtle has moved ``metres`` along its path."""
    while launch.elapsed() < within:
        if all(travelled(observer.samples[t]) >= metres for t in topics):
            return
        assert launch.proc.poll() is None, f"launch exited early:\n{launch.output()}"
        time.sleep(0.05)
    paths = {t: round(travelled(observer.samples[t]), 2) for t in topics}
    pytest.fail(f"turtles did not travel {metres} m in {within} s: {paths}\n{launch.output()}")


@pytest.mark.timeout(60)
def test_start_tf_demo_auto_driver_turtle2_reaches_turtle1_within_15_seconds(run_demo):
    launch, observer = run_demo(["learning_tf", "start_tf_demo.launch", "driver:=auto"],
                                ["/turtle1/pose", "/turtle2/pose"])
    wait_until_close(launch, observer, "/turtle1/pose", "/turtle2/pose", within=15.0)
    # turtle1 really is driven (not a follower closing on a parked leader)
    xs = [s["x"] for s in observer.samples["/turtle1/pose"]]
    assert max(xs) - min(xs) > 1.0
    assert launch.stop() == 0


@pytest.mark.timeout(60)
def test_turtle_tf_demo_snapshot_shows_both_turtles_trails(run_demo, tmp_path):
    from test_turtlesim_world import read_png

    png = tmp_path / "turtle_tf.png"
    launch, observer = run_demo(["turtle_tf", "turtle_tf_demo.launch", "driver:=auto",
                                 f"snapshot:={png}"], ["/turtle1/pose", "/turtle2/pose"])
    wait_until_close(launch, observer, "/turtle1/pose", "/turtle2/pose", within=15.0)
    # let both draw trails of several metres (the pen-pixel count below needs them)
    wait_until_travelled(launch, observer, ("/turtle1/pose", "/turtle2/pose"), 5.0, within=30.0)
    assert launch.stop() == 0
    width, height, pixels = read_png(png.read_bytes())  # written at shutdown
    assert (width, height) == (500, 500)

    def pixel(x_m: float, y_m: float) -> tuple[int, int, int]:
        px, py = int(x_m * PX_PER_METER), int((WORLD - y_m) * PX_PER_METER)
        i = (py * width + px) * 3
        return tuple(pixels[i:i + 3])

    # each trail starts where its turtle started: turtle1 in the centre, turtle2 at (4, 2)
    assert pixel(WORLD / 2, WORLD / 2) == PEN
    assert pixel(4.0, 2.0) == PEN
    # and both follow the turtles' observed paths (sampled a few seconds in)
    for topic in ("/turtle1/pose", "/turtle2/pose"):
        samples = observer.samples[topic]
        mid = samples[len(samples) // 2]
        assert pixel(mid["x"], mid["y"]) == PEN, topic
    pen_pixels = sum(1 for i in range(0, len(pixels), 3) if tuple(pixels[i:i + 3]) == PEN)
    assert pen_pixels > 800  # two 3 px wide trails several metres long


def angle_diff(a: float, b: float) -> float:
    return abs((a - b + math.pi) % (2 * math.pi) - math.pi)


@pytest.mark.timeout(60)
def test_multi_turtle_mimic_turtlesim2_turtle_tracks_turtlesim1_heading(run_demo):
    leader, mimic = "/turtlesim1/turtle1/pose", "/turtlesim2/turtle1/pose"
    launch, observer = run_demo([str(REPO / "launch" / "multi_turtle.launch"), "driver:=auto"],
                                [leader, mimic])
    turned_at = None
    while launch.elapsed() < 25.0:
        assert launch.proc.poll() is None, f"launch exited early:\n{launch.output()}"
        headings = [s["theta"] for s in observer.samples[leader]]
        if turned_at is None and headings and max(headings) - min(headings) > 1.2:
            turned_at = launch.elapsed()
        if turned_at is not None and launch.elapsed() > turned_at + 1.5:
            break
        time.sleep(0.1)
    assert launch.stop() == 0
    lead, follow = observer.samples[leader], observer.samples[mimic]
    assert lead and follow
    headings = [s["theta"] for s in lead]
    assert max(headings) - min(headings) > 1.0, "turtlesim1/turtle1 never turned"
    # compare each mimic sample with the leader's sample of about the same moment
    diffs = []
    j = 0
    for s in follow:
        while j + 1 < len(lead) and lead[j + 1]["t"] <= s["t"]:
            j += 1
        diffs.append(angle_diff(s["theta"], lead[j]["theta"]))
    diffs.sort()
    print(f"heading difference: median {diffs[len(diffs) // 2]:.3f} max {diffs[-1]:.3f} "
          f"over {len(diffs)} samples; leader turned {max(headings) - min(headings):.2f} rad")
    assert diffs[len(diffs) // 2] < 0.1
    assert diffs[int(len(diffs) * 0.95)] < 0.3


def observe(topics: list[str]) -> None:
    """Observer process: print every turtlesim/Pose of ``topics`` as a JSON line."""
    import orchestra.node as node
    from orchestra.master import master_is_up

    uri = os.environ["ROS_MASTER_URI"]
    deadline = time.monotonic() + 30
    while not master_is_up(uri):
        if time.monotonic() > deadline:
            sys.exit("no master")
        time.sleep(0.05)
    node.init_node("demo_observer", anonymous=True)
    pose = node.get_message_class("turtlesim/Pose")
    lock = threading.Lock()

    def callback(topic: str):
        def on_pose(msg) -> None:
            line = json.dumps({"topic": topic, "t": time.monotonic(), "x": msg.x, "y": msg.y,
                               "theta": msg.theta})
            with lock:
                sys.stdout.write(line + "\n")
                sys.stdout.flush()
        return on_pose

    for topic in topics:
        node.Subscriber(topic, pose, callback(topic), queue_size=100)
    node.spin()


if __name__ == "__main__" and len(sys.argv) > 2 and sys.argv[1] == "observe":
    observe(sys.argv[2:])
