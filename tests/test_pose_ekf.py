"""robot_pose_ekf's planar filter: relative odometry, IMU heading fusion, covariance."""
from __future__ import annotations

import math
import random
import sys
from pathlib import Path

import pytest

PACKAGES = Path(__file__).resolve().parent.parent / "packages"
sys.path.insert(0, str(PACKAGES / "robot_pose_ekf" / "src"))

from robot_pose_ekf.ekf import PlanarEKF, relative_motion  # noqa: E402


def test_relative_motion_is_expressed_in_previous_robot_frame():
    dx, dy, dyaw = relative_motion((1.0, 1.0, math.pi / 2), (1.0, 2.0, math.pi / 2))
    assert (dx, dy, dyaw) == pytest.approx((1.0, 0.0, 0.0), abs=1e-12)


def test_first_odometry_initialises_the_filter_there():
    ekf = PlanarEKF()
    assert not ekf.initialized
    ekf.add_odometry((2.0, -1.0, 0.3))
    assert ekf.initialized and ekf.state() == pytest.approx((2.0, -1.0, 0.3))


def test_odometry_only_follows_odometry_and_grows_uncertainty_with_distance():
    ekf = PlanarEKF()
    ekf.add_odometry((0.0, 0.0, 0.0))
    p0 = ekf.P[0][0]
    for i in range(1, 11):
        ekf.add_odometry((0.1 * i, 0.0, 0.0))
    assert ekf.state() == pytest.approx((1.0, 0.0, 0.0), abs=1e-9)
    assert ekf.P[0][0] > p0


def test_standing_still_does_not_grow_uncertainty_noticeably():
    ekf = PlanarEKF()
    for _ in range(100):
        ekf.add_odometry((0.0, 0.0, 0.0))
    assert ekf.P[0][0] < 1e-3


def test_imu_heading_corrects_drifting_odometry_heading():
    rng = random.Random(1)
    ekf = PlanarEKF()
    true_yaw = 0.0
    odom_yaw = 0.0
    x = y = 0.0
    ekf.add_odometry((x, y, odom_yaw))
    ekf.add_imu(0.0, 0.001)               # aligns the imu with the filter
    for _ in range(200):
        true_yaw += 0.01
        odom_yaw += 0.01 * 1.2            # odometry over-reports rotation by 20 %
        x += 0.01 * math.cos(odom_yaw)
        y += 0.01 * math.sin(odom_yaw)
        ekf.add_odometry((x, y, odom_yaw))
        ekf.add_imu(true_yaw + rng.gauss(0.0, 0.005), 0.001)
    assert abs(ekf.yaw - true_yaw) < 0.05
    assert abs(odom_yaw - true_yaw) > 0.3


def test_imu_update_shrinks_heading_variance():
    ekf = PlanarEKF()
    ekf.add_odometry((0.0, 0.0, 0.0))
    ekf.add_imu(0.0)
    ekf.add_odometry((0.0, 0.0, 1.0))      # a turn: heading becomes uncertain
    before = ekf.P[2][2]
    ekf.add_imu(1.0, 0.001)
    assert ekf.P[2][2] < before


def test_imu_before_odometry_is_ignored():
    ekf = PlanarEKF()
    ekf.add_imu(1.0)
    assert not ekf.initialized and ekf.yaw == 0.0


def test_heading_wraps_across_pi():
    ekf = PlanarEKF()
    ekf.add_odometry((0.0, 0.0, 3.1))
    ekf.add_odometry((0.0, 0.0, -3.1))    # +0.083 rad across the wrap
    assert ekf.yaw == pytest.approx(-3.1, abs=1e-9)


def test_covariance_6x6_layout_puts_yaw_at_35_and_is_symmetric():
    ekf = PlanarEKF()
    ekf.add_odometry((0.0, 0.0, 0.0))
    ekf.add_odometry((1.0, 0.5, 0.4))
    cov = ekf.covariance_6x6()
    assert len(cov) == 36
    assert cov[35] == pytest.approx(ekf.P[2][2])
    assert cov[0] == pytest.approx(ekf.P[0][0]) and cov[7] == pytest.approx(ekf.P[1][1])
    for r in range(6):
        for c in range(6):
            assert cov[r * 6 + c] == pytest.approx(cov[c * 6 + r])
    assert cov[14] == 1e6   # z is unobserved
