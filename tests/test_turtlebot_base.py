"""The simulated Kobuki base's maths: kinematics, encoders, odometry, watchdog, battery."""
from __future__ import annotations

import math
import sys
from pathlib import Path

import pytest

PACKAGES = Path(__file__).resolve().parent.parent / "packages"
sys.path.insert(0, str(PACKAGES / "kobuki_node" / "src"))

from kobuki_node.base import (  # noqa: E402
    TICK_TO_RAD,
    WHEEL_BASE,
    WHEEL_RADIUS,
    BatteryModel,
    KobukiBase,
    Pose2D,
    integrate_pose,
    normalize_angle,
    odometry_step,
    quaternion_to_yaw,
    tick_delta,
    wheel_speeds,
    yaw_to_quaternion,
)


def test_straight_line_integration_moves_along_heading():
    pose = integrate_pose(Pose2D(1.0, 2.0, math.pi / 2), 0.5, 0.0, 2.0)
    assert pose.x == pytest.approx(1.0)
    assert pose.y == pytest.approx(3.0)
    assert pose.theta == pytest.approx(math.pi / 2)


def test_full_circle_in_small_steps_closes_on_itself():
    pose = Pose2D()
    for _ in range(1000):
        pose = integrate_pose(pose, 0.2, 2 * math.pi / 10.0, 0.01)  # one turn in 10 s
    assert pose.x == pytest.approx(0.0, abs=1e-9)
    assert pose.y == pytest.approx(0.0, abs=1e-9)
    assert normalize_angle(pose.theta) == pytest.approx(0.0, abs=1e-9)


def test_arc_reaches_the_circle_point():
    # quarter circle of radius 1 starting at the origin facing +x turning left
    pose = integrate_pose(Pose2D(), 1.0, 1.0, math.pi / 2)
    assert (pose.x, pose.y) == pytest.approx((1.0, 1.0))
    assert pose.theta == pytest.approx(math.pi / 2)


def test_wheel_speeds_of_a_pure_rotation_are_opposite():
    left, right = wheel_speeds(0.0, 1.0)
    assert left == pytest.approx(-right)
    assert right == pytest.approx(WHEEL_BASE / 2 / WHEEL_RADIUS)


def test_tick_delta_handles_uint16_wrap_both_ways():
    assert tick_delta(65530, 4) == 10
    assert tick_delta(4, 65530) == -10
    assert tick_delta(100, 250) == 150


def test_odometry_from_ticks_forward_distance():
    ticks = round(1.0 / (TICK_TO_RAD * WHEEL_RADIUS))  # ~1 m worth of ticks per wheel
    pose, distance, rotation = odometry_step(Pose2D(), ticks, ticks)
    assert distance == pytest.approx(1.0, rel=1e-3)
    assert rotation == pytest.approx(0.0)
    assert pose.x == pytest.approx(1.0, rel=1e-3)


def test_odometry_uses_gyro_heading_for_rotation_when_given():
    pose, _, rotation = odometry_step(Pose2D(theta=0.1), 0, 100, heading=0.5)
    assert rotation == pytest.approx(0.4)
    assert pose.theta == pytest.approx(0.5)


def test_base_odometry_follows_commanded_motion_through_encoders():
    base = KobukiBase(cmd_vel_timeout=10.0)
    base.command(0.2, 0.0, now=0.0)
    t = 0.0
    for _ in range(100):
        t += 0.05
        base.step(t, 0.05)
    assert base.odom_pose.x == pytest.approx(1.0, abs=0.01)   # 0.2 m/s for 5 s
    assert base.true_pose.x == pytest.approx(1.0, abs=1e-9)
    assert base.odom_pose.y == pytest.approx(0.0, abs=1e-6)


def test_base_turns_in_place_with_heading_from_gyro():
    base = KobukiBase(cmd_vel_timeout=10.0)
    base.command(0.0, 0.5, now=0.0)
    t = 0.0
    for _ in range(20):
        t += 0.1
        base.step(t, 0.1)
    assert base.odom_pose.theta == pytest.approx(1.0, abs=1e-6)
    assert math.hypot(base.odom_pose.x, base.odom_pose.y) < 1e-3


def test_base_stops_when_commands_time_out():
    base = KobukiBase(cmd_vel_timeout=0.6)
    base.command(0.3, 0.0, now=0.0)
    base.step(0.5, 0.5)
    assert base.v == 0.3
    base.step(1.0, 0.5)          # command is 1.0 s old > 0.6 s
    assert base.v == 0.0
    assert base.true_pose.x == pytest.approx(0.15)


def test_disabled_motors_ignore_commands_and_warn_in_diagnostics():
    base = KobukiBase()
    base.motors_enabled = False
    base.command(0.3, 0.0, now=0.0)
    base.step(0.1, 0.1)
    assert base.true_pose.x == 0.0
    motor = [d for d in base.diagnostics("mgr") if d.name == "mgr: Motor State"][0]
    assert motor.level == 1


def test_diagnostics_are_prefixed_with_the_hosting_node_name():
    names = [d.name for d in KobukiBase().diagnostics("mobile_base_nodelet_manager")]
    assert "mobile_base_nodelet_manager: Battery" in names
    assert "mobile_base_nodelet_manager: Watchdog" in names


def test_battery_levels_follow_thresholds():
    battery = BatteryModel(capacity=16.5, low=14.0, dangerous=13.2, voltage=16.5)
    assert battery.status()[0] == 0 and battery.percent == pytest.approx(100.0)
    battery.voltage = 13.9
    assert battery.status() == (1, "Low Power")
    battery.voltage = 13.0
    assert battery.status() == (2, "Critical Power")
    assert battery.percent == 0.0


def test_yaw_quaternion_round_trip():
    for yaw in (-3.0, -1.0, 0.0, 0.7, 3.1):
        assert quaternion_to_yaw(*yaw_to_quaternion(yaw)) == pytest.approx(yaw)
