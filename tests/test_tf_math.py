"""Quaternion and rigid-transform math of orchestra.tf.transformations."""
from __future__ import annotations

import math

import pytest

from orchestra.tf import transformations as tfm


def close(a, b, tol=1e-9):
    return all(abs(x - y) <= tol for x, y in zip(a, b, strict=False))


def test_quaternion_from_euler_yaw_only_is_rotation_about_z():
    q = tfm.quaternion_from_euler(0.0, 0.0, math.pi / 2)
    assert close(q, (0.0, 0.0, math.sin(math.pi / 4), math.cos(math.pi / 4)))


def test_euler_roundtrip_for_general_angles():
    for rpy in [(0.1, -0.4, 2.5), (-1.2, 0.7, -3.0), (0.0, 0.0, 0.0)]:
        assert close(tfm.euler_from_quaternion(tfm.quaternion_from_euler(*rpy)), rpy, 1e-9)


def test_rotate_vector_by_quarter_turn_about_z_maps_x_to_y():
    q = tfm.quaternion_from_euler(0, 0, math.pi / 2)
    assert close(tfm.rotate_vector(q, (1.0, 0.0, 0.0)), (0.0, 1.0, 0.0))


def test_roll_then_yaw_order_matches_static_xyz_axes():
    # sxyz: roll about X first, then yaw about static Z: (0,1,0) -> (0,0,1) -> (0,0,1)
    q = tfm.quaternion_from_euler(math.pi / 2, 0, math.pi / 2)
    assert close(tfm.rotate_vector(q, (0.0, 1.0, 0.0)), (0.0, 0.0, 1.0))
    assert close(tfm.rotate_vector(q, (1.0, 0.0, 0.0)), (0.0, 1.0, 0.0))


def test_multiply_applies_right_operand_first():
    qx = tfm.quaternion_from_euler(math.pi / 2, 0, 0)
    qz = tfm.quaternion_from_euler(0, 0, math.pi / 2)
    both = tfm.quaternion_multiply(qz, qx)
    assert close(both, tfm.quaternion_from_euler(math.pi / 2, 0, math.pi / 2))


def test_compose_with_inverse_is_identity():
    t = ((1.0, 2.0, 3.0), tfm.quaternion_from_euler(0.3, -0.2, 1.1))
    trans, rot = tfm.compose(t, tfm.inverse(t))
    assert close(trans, (0, 0, 0))
    assert close(rot, tfm.IDENTITY_QUATERNION) or close(rot, (0, 0, 0, -1))


def test_transform_point_rotates_then_translates():
    t = ((1.0, 0.0, 0.0), tfm.quaternion_from_euler(0, 0, math.pi))
    assert close(tfm.transform_point(t, (1.0, 0.0, 0.0)), (0.0, 0.0, 0.0))


def test_slerp_halfway_between_zero_and_right_angle_is_45_degrees():
    q0 = tfm.quaternion_from_euler(0, 0, 0)
    q1 = tfm.quaternion_from_euler(0, 0, math.pi / 2)
    assert math.isclose(tfm.yaw_from_quaternion(tfm.quaternion_slerp(q0, q1, 0.5)),
                        math.pi / 4, abs_tol=1e-9)


def test_slerp_takes_the_short_arc_across_pi():
    q0 = tfm.quaternion_from_euler(0, 0, math.pi - 0.1)
    q1 = tfm.quaternion_from_euler(0, 0, -math.pi + 0.1)
    yaw = tfm.yaw_from_quaternion(tfm.quaternion_slerp(q0, q1, 0.5))
    assert math.isclose(abs(yaw), math.pi, abs_tol=1e-6)


def test_zero_quaternion_is_rejected():
    with pytest.raises(ValueError):
        tfm.normalize((0, 0, 0, 0))
