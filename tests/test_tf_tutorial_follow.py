"""The tf tutorial's rules without processes: the follower law, pose->transform, and the whole
chase simulated on turtlesim's world with the transform tree in between."""
from __future__ import annotations

import math
import sys
from pathlib import Path

import pytest

PKGS = Path(__file__).resolve().parent.parent / "packages"
sys.path.insert(0, str(PKGS / "turtlesim" / "src"))
sys.path.insert(0, str(PKGS / "learning_tf" / "src"))

from learning_tf_core.follow import follow_command, pose_to_transform  # noqa: E402
from turtlesim_core import world as W  # noqa: E402
from turtlesim_core.driving import Circuit  # noqa: E402

from orchestra.tf.buffer import TransformBuffer  # noqa: E402
from orchestra.tf.transformations import yaw_from_quaternion  # noqa: E402


def test_follow_command_uses_tutorial_gains():
    linear, angular = follow_command(3.0, 4.0)
    assert linear == pytest.approx(0.5 * 5.0)
    assert angular == pytest.approx(4.0 * math.atan2(4.0, 3.0))


def test_target_straight_ahead_needs_no_turn_and_behind_turns_hardest():
    assert follow_command(2.0, 0.0) == pytest.approx((1.0, 0.0))
    assert follow_command(-1.0, 1e-9)[1] == pytest.approx(4.0 * math.pi)


def test_pose_to_transform_puts_turtle_in_plane_with_its_heading():
    translation, rotation = pose_to_transform(1.5, 2.5, 0.7)
    assert translation == (1.5, 2.5, 0.0)
    assert yaw_from_quaternion(rotation) == pytest.approx(0.7)


def simulate_chase(seconds: float) -> list[float]:
    """turtle1 on the auto-driver circuit, turtle2 spawned at (4, 2) following through tf at
    10 Hz, on a 16 ms world tick: the distance between them, sampled at 10 Hz."""
    world = W.World()
    leader = world.reset(W.DEFAULT_BACKGROUND)
    follower = world.spawn("turtle2", 4.0, 2.0, 0.0)
    driver = Circuit()
    buf = TransformBuffer()
    distances = []
    ticks = int(seconds / W.UPDATE_PERIOD)
    for k in range(ticks):
        now = k * W.UPDATE_PERIOD
        if k % 3 == 0:  # the driver's 20 Hz
            leader.command(*driver.command(leader.x, leader.y, leader.theta, now), now)
        world.step(now)
        for t in (leader, follower):
            buf.set_transform("world", t.name, now, pose_to_transform(t.x, t.y, t.theta))
        if k % 6 == 0:  # the listener's ~10 Hz
            (trans, _), _ = buf.lookup("turtle2", "turtle1", 0.0)
            follower.command(*follow_command(trans[0], trans[1]), now)
            distances.append(math.hypot(leader.x - follower.x, leader.y - follower.y))
    return distances


def test_follower_closes_on_the_auto_driven_leader_within_15_seconds():
    distances = simulate_chase(15.0)
    assert distances[0] > 3.0
    assert min(distances) < 1.0


def test_follower_keeps_up_over_a_full_circuit():
    distances = simulate_chase(60.0)
    late = distances[len(distances) // 4:]
    assert max(late) < 3.0  # never left far behind
    assert sum(d < 1.0 for d in late) > len(late) // 4  # and close for a good part of it
