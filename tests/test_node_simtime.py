"""Simulated time (/use_sim_time + /clock), end to end with real node processes.

A ``clock`` process publishes /clock values the test sends it; a ``follow`` node runs the
time API on command (tests/node_fixtures/simtime.py) and reports what it sees. The sim
clock only moves when the test says so, so every expected time is exact. With Debian's
rospy installed, the same follower script also runs on rospy (sleep and a backwards jump:
the behaviour to match), and a real rospy /clock publisher drives an orchestra node.
A few rules (Rate reset, shutdown) are checked in process with the clock set by hand.
"""
from __future__ import annotations

import functools
import os
import signal
import subprocess
import sys
import threading
import time
import xmlrpc.client
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent / "node_fixtures"))
from harness import NodeProcess  # noqa: E402

from orchestra.node import rostime  # noqa: E402
from orchestra.node.exceptions import ROSInterruptException, ROSTimeMovedBackwardsException  # noqa: E402

pytestmark = pytest.mark.timeout(60)

SCRIPT = Path(__file__).resolve().parent / "node_fixtures" / "simtime.py"
ROS_PYTHON = "/usr/bin/python3"
S = 1_000_000_000  # ns per second


def ns(secs: float) -> int:
    return round(secs * S)


class Driven(NodeProcess):
    """A harness NodeProcess with a stdin pipe: ``send`` writes one command line."""

    def __init__(self, argv: list[str], env: dict[str, str]):
        super().__init__(argv, env, stdin=subprocess.PIPE)

    def send(self, line: str) -> None:
        self.proc.stdin.write(line + "\n")
        self.proc.stdin.flush()

    def get(self, key: str, timeout: float = 10.0) -> dict:
        """The next report that has ``key``."""
        return self.expect(lambda d: key in d, timeout)

    def nothing_new(self, wait: float) -> list:
        """The first report that arrives within ``wait`` seconds, as a list (expected: [])."""
        try:
            return [self.expect(lambda d: True, wait)]
        except AssertionError:
            return []


class SimWorld:
    """A clock publisher and followers against one master; ``close()`` ends them all."""

    def __init__(self, nodes, ros_home: Path):
        self.nodes = nodes
        self.ros_home = ros_home  # real rospy writes its logs there, not in ~/.ros
        self.procs: list[Driven] = []
        self.clock: Driven | None = None

    def start(self, mode: str, ros1: bool = False) -> Driven:
        if ros1:
            argv = [ROS_PYTHON, str(SCRIPT), "--ros1", mode]
            env = _ros_env(dict(self.nodes.env, ROS_HOME=str(self.ros_home)))
        else:
            argv, env = [sys.executable, str(SCRIPT), mode], dict(self.nodes.env)
        proc = Driven(argv, env)
        self.procs.append(proc)
        return proc

    def start_clock(self, ros1: bool = False) -> Driven:
        self.clock = self.start("clock", ros1)
        self.clock.get("ready", 20)
        return self.clock

    def publish(self, secs: float) -> None:
        self.clock.send(repr(secs))
        self.clock.get("published")

    def close(self) -> None:
        for proc in self.procs:  # end of input ends the command loop, SIGTERM the node
            try:
                proc.proc.stdin.close()
            except OSError:
                pass
            proc.signal(signal.SIGTERM)
        for proc in self.procs:
            try:
                proc.proc.wait(5)
            except subprocess.TimeoutExpired:
                proc.kill()
            proc.close_pipes()


@functools.cache
def _rospy_missing() -> str | None:
    """Why Debian's real rospy cannot run here (None: it can); probed once."""
    if not os.access(ROS_PYTHON, os.X_OK):
        return f"{ROS_PYTHON} is not installed"
    probe = subprocess.run([ROS_PYTHON, "-c", "import rospy, rosgraph_msgs.msg"],
                           capture_output=True, text=True, env=_ros_env({}))
    return None if probe.returncode == 0 else "Debian's rospy is not installed"


def _ros_env(base: dict[str, str]) -> dict[str, str]:
    """For a real-ROS process: only the ROS_ variables of the test, no orchestra Python."""
    env = {k: v for k, v in os.environ.items()
           if not k.startswith(("PYTHON", "ROS_", "VIRTUAL_ENV", "PYENV"))}
    env.update({k: v for k, v in base.items() if k.startswith("ROS_")}, PYTHONUNBUFFERED="1")
    return env


@pytest.fixture
def world(nodes, tmp_path):
    group = SimWorld(nodes, tmp_path / "ros_home")
    yield group
    group.close()


@pytest.fixture
def sim_world(world, master):
    master.params.set("/use_sim_time", True)
    return world


def follow_at(world: SimWorld, secs: float, ros1: bool = False) -> Driven:
    """A follower whose clock reads ``secs`` (the clock process is up)."""
    follower = world.start("follow", ros1)
    follower.get("ready", 20)
    world.publish(secs)
    follower.send(f"until {ns(secs)}")
    assert follower.get("now")["now"] == ns(secs)
    return follower


def clock_subscribers(master_uri: str) -> list[str]:
    with xmlrpc.client.ServerProxy(master_uri) as master:
        _, _, (_, subs, _) = master.getSystemState("/t")
    return dict((topic, nodes) for topic, nodes in subs).get("/clock", [])


# --- simulated time --------------------------------------------------------------------------

def test_time_is_zero_until_the_first_clock_then_follows_it(sim_world, master):
    follower = sim_world.start("follow")
    ready = follower.get("ready", 20)
    assert (ready["now"], ready["time"]) == (0, 0.0)  # no /clock publisher yet
    assert clock_subscribers(master.uri) == ["/follower"]
    sim_world.start_clock()
    for secs in (5.0, 7.25, 1000.5):
        sim_world.publish(secs)
        follower.send(f"until {ns(secs)}")
        got = follower.get("now")
        assert (got["now"], got["time"]) == (ns(secs), secs)


def test_rate_sleep_wakes_only_when_the_clock_reaches_each_period(sim_world):
    sim_world.start_clock()
    follower = follow_at(sim_world, 100.0)
    follower.send("rate 10 2")  # 0.1 s periods of sim time: due at 100.1 and 100.2
    assert follower.get("rate")["rate"] == 100 * S
    assert follower.nothing_new(0.5) == []  # 5 wall periods pass, the sim clock stands still
    sim_world.publish(100.05)
    sim_world.publish(100.1)
    assert follower.get("tick") == {"tick": 0, "now": ns(100.1)}  # not woken at 100.05
    sim_world.publish(100.3)  # past the second deadline
    assert follower.get("tick") == {"tick": 1, "now": ns(100.3)}


@pytest.mark.parametrize("impl", ["orchestra", "rospy"])
def test_sleep_follows_the_clock_and_raises_when_it_jumps_backwards(sim_world, impl):
    """The same script on orchestra and, when installed, on Debian's real rospy."""
    if impl == "rospy" and _rospy_missing():
        pytest.skip(_rospy_missing())
    sim_world.start_clock()
    follower = follow_at(sim_world, 50.0, ros1=impl == "rospy")
    follower.send("sleep 1")
    assert follower.get("sleeping")["sleeping"] == 50 * S
    sim_world.publish(50.5)
    sim_world.publish(51.0)
    assert follower.get("slept")["slept"] == 51 * S
    follower.send("sleep 5")
    follower.get("sleeping")
    sim_world.publish(41.0)
    assert follower.get("error") == {"error": "ROSTimeMovedBackwardsException",
                                     "interrupt": True, "jump": 10.0}


def test_timer_ticks_on_sim_time_and_a_stopped_clock_sleep_wakes_at_shutdown(sim_world):
    sim_world.start_clock()
    follower = follow_at(sim_world, 10.0)
    follower.send("timer 1.0")
    follower.get("timer")
    sim_world.publish(10.5)
    sim_world.publish(11.0)
    assert follower.get("fired") == {"fired": 11 * S, "expected": 11 * S}
    sim_world.publish(13.5)  # the tick due at 12 runs late; the one due at 13 is skipped
    assert follower.get("fired") == {"fired": ns(13.5), "expected": 12 * S}
    sim_world.publish(14.0)
    assert follower.get("fired") == {"fired": 14 * S, "expected": 14 * S}
    follower.send("sleep 60")
    follower.get("sleeping")
    follower.signal(signal.SIGTERM)
    assert follower.get("error") == {"error": "ROSInterruptException", "interrupt": True}
    assert follower.wait(10) == 0


def test_without_use_sim_time_time_is_wall_time_and_clock_is_ignored(world, master):
    world.start_clock()
    world.publish(5.0)
    follower = world.start("follow")
    ready = follower.get("ready", 20)
    assert abs(ready["now"] / S - time.time()) < 60 and abs(ready["time"] - time.time()) < 60
    assert clock_subscribers(master.uri) == []
    follower.send("sleep 0.05")  # a wall-clock sleep: ends without any /clock
    follower.get("slept")
    follower.send("now")
    assert abs(follower.get("now")["now"] / S - time.time()) < 60


def test_topic_pub_can_be_the_clock_under_use_sim_time(sim_world):
    """``orchestra topic pub -r`` stays on wall time (rostopic pub's default), so it can
    publish /clock itself."""
    follower = sim_world.start("follow")
    follower.get("ready", 20)
    sim_world.nodes.start_orchestra("topic", "pub", "-r", "20", "/clock",
                                    "rosgraph_msgs/Clock", "clock: {secs: 42, nsecs: 5}")
    follower.send(f"until {42 * S + 5}")
    assert follower.get("now")["now"] == 42 * S + 5


# --- rules, in process (the clock set by hand) --------------------------------------------

@pytest.fixture
def sim_clock():
    """This process on simulated time at 10 s (its own shutdown event); as before after."""
    previous = rostime._sim_ns, rostime._shutdown_event
    event = threading.Event()
    rostime._set_shutdown_event(event)
    rostime._use_sim_time()
    rostime._set_sim_time(rostime.Time(10))
    yield event
    event.set()
    rostime._wake_sleepers()
    rostime._sim_ns = previous[0]
    rostime._set_shutdown_event(previous[1])


def blocked_then(sleep, action) -> BaseException | None:
    """Run ``sleep`` in a thread; once it waits on the clock, run ``action``. Returns what
    ``sleep`` raised (None: it returned). The interrupts are KeyboardInterrupts: kept off
    pytest's thread, an unexpected one fails this test instead of ending the session."""
    outcome: list = []

    def target():
        try:
            sleep()
            outcome.append(None)
        except BaseException as exc:  # noqa: B902 - handed to the test
            outcome.append(exc)

    thread = threading.Thread(target=target, daemon=True)
    thread.start()
    deadline = time.monotonic() + 10
    while thread.is_alive() and time.monotonic() < deadline:
        frame = sys._current_frames().get(thread.ident)
        if frame is not None and frame.f_code.co_name == "wait" \
                and frame.f_code.co_filename == threading.__file__:
            break
        time.sleep(0.002)
    action()
    thread.join(10)
    assert not thread.is_alive(), "still sleeping"
    return outcome[0]


def test_rate_with_reset_restarts_after_a_backwards_jump_instead_of_raising(sim_clock):
    def jump_back():
        rostime._set_sim_time(rostime.Time(3))

    raised = blocked_then(rostime.Rate(1).sleep, jump_back)
    assert isinstance(raised, ROSTimeMovedBackwardsException) and raised.time == 7.0
    rostime._set_sim_time(rostime.Time(10))
    resetting = rostime.Rate(1, reset=True)
    assert blocked_then(resetting.sleep, jump_back) is None  # returns at the jump
    assert resetting.remaining() == rostime.Duration(1)  # schedule restarted at 3 s


def test_a_jump_back_between_sleeps_restarts_the_schedule_and_shutdown_interrupts(sim_clock):
    rate = rostime.Rate(2)
    rostime._set_sim_time(rostime.Time(4))  # back from 10 before the first sleep
    assert rate.remaining() == rostime.Duration(0, 500_000_000)

    def shut_down():
        sim_clock.set()
        rostime._wake_sleepers()

    raised = blocked_then(rate.sleep, shut_down)
    assert type(raised) is ROSInterruptException
    assert rostime.Time.now() == rostime.Time(4) and not rostime.is_wallclock()


# --- interop: a real rospy node is the clock ------------------------------------------------

@pytest.mark.timeout(90)
def test_orchestra_node_follows_a_real_rospy_clock_publisher(sim_world):
    missing = _rospy_missing()
    if missing:
        pytest.skip(missing)
    sim_world.start_clock(ros1=True)
    follower = follow_at(sim_world, 20.0)
    follower.send("rate 4 1")
    follower.get("rate")
    sim_world.publish(20.25)
    assert follower.get("tick") == {"tick": 0, "now": ns(20.25)}
