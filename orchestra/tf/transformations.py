"""Quaternion and rigid-transform math in pure Python, in tf's conventions.

Quaternions are ``(x, y, z, w)`` tuples like tf/tf2 and geometry_msgs; Euler angles are
roll-pitch-yaw about static axes X, Y, Z (tf.transformations' default ``'sxyz'``), which is
what ``static_transform_publisher x y z yaw pitch roll`` and every tutorial mean. A rigid
transform is ``(translation, rotation)``: the pose of a child frame in its parent frame.

Pure functions over tuples (no numpy) because the transforms are few and small and the
library must import in milliseconds inside every node.
"""
from __future__ import annotations

import math
from collections.abc import Sequence

Vector = tuple[float, float, float]
Quaternion = tuple[float, float, float, float]
Transform = tuple[Vector, Quaternion]

IDENTITY_QUATERNION: Quaternion = (0.0, 0.0, 0.0, 1.0)
IDENTITY: Transform = ((0.0, 0.0, 0.0), IDENTITY_QUATERNION)


def quaternion_from_euler(roll: float, pitch: float, yaw: float) -> Quaternion:
    """Quaternion for a rotation of ``roll`` about X, then ``pitch`` about Y, then ``yaw`` about Z
    (static axes)."""
    cr, sr = math.cos(roll / 2.0), math.sin(roll / 2.0)
    cp, sp = math.cos(pitch / 2.0), math.sin(pitch / 2.0)
    cy, sy = math.cos(yaw / 2.0), math.sin(yaw / 2.0)
    return (
        sr * cp * cy - cr * sp * sy,
        cr * sp * cy + sr * cp * sy,
        cr * cp * sy - sr * sp * cy,
        cr * cp * cy + sr * sp * sy,
    )


def euler_from_quaternion(q: Sequence[float]) -> Vector:
    """(roll, pitch, yaw) of a quaternion; pitch is clamped at ±pi/2 (gimbal lock)."""
    x, y, z, w = normalize(q)
    roll = math.atan2(2.0 * (w * x + y * z), 1.0 - 2.0 * (x * x + y * y))
    sinp = max(-1.0, min(1.0, 2.0 * (w * y - z * x)))
    pitch = math.asin(sinp)
    yaw = math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))
    return (roll, pitch, yaw)


def normalize(q: Sequence[float]) -> Quaternion:
    """Unit quaternion; a zero quaternion is a user error (tf rejects it too)."""
    n = math.sqrt(sum(c * c for c in q))
    if n == 0.0:
        raise ValueError("quaternion has zero length")
    return (q[0] / n, q[1] / n, q[2] / n, q[3] / n)


def quaternion_multiply(a: Sequence[float], b: Sequence[float]) -> Quaternion:
    """Hamilton product ``a * b``: rotate by ``b`` first, then by ``a``."""
    ax, ay, az, aw = a
    bx, by, bz, bw = b
    return (
        aw * bx + ax * bw + ay * bz - az * by,
        aw * by - ax * bz + ay * bw + az * bx,
        aw * bz + ax * by - ay * bx + az * bw,
        aw * bw - ax * bx - ay * by - az * bz,
    )


def quaternion_conjugate(q: Sequence[float]) -> Quaternion:
    return (-q[0], -q[1], -q[2], q[3])


def quaternion_inverse(q: Sequence[float]) -> Quaternion:
    n2 = sum(c * c for c in q)
    if n2 == 0.0:
        raise ValueError("quaternion has zero length")
    c = quaternion_conjugate(q)
    return (c[0] / n2, c[1] / n2, c[2] / n2, c[3] / n2)


def rotate_vector(q: Sequence[float], v: Sequence[float]) -> Vector:
    """``v`` rotated by unit quaternion ``q`` (q * v * q^-1, expanded)."""
    x, y, z, w = q
    vx, vy, vz = v
    # t = 2 * cross(q.xyz, v); v' = v + w * t + cross(q.xyz, t)
    tx = 2.0 * (y * vz - z * vy)
    ty = 2.0 * (z * vx - x * vz)
    tz = 2.0 * (x * vy - y * vx)
    return (
        vx + w * tx + (y * tz - z * ty),
        vy + w * ty + (z * tx - x * tz),
        vz + w * tz + (x * ty - y * tx),
    )


def quaternion_slerp(q0: Sequence[float], q1: Sequence[float], fraction: float) -> Quaternion:
    """Spherical interpolation along the short arc (what tf does between two stamped samples)."""
    q0 = normalize(q0)
    q1 = normalize(q1)
    dot = sum(a * b for a, b in zip(q0, q1, strict=False))
    if dot < 0.0:  # the short way round
        q1 = (-q1[0], -q1[1], -q1[2], -q1[3])
        dot = -dot
    if dot > 0.9995:  # nearly parallel: lerp is exact enough and avoids dividing by ~0
        return normalize(tuple(a + fraction * (b - a) for a, b in zip(q0, q1, strict=False)))
    theta = math.acos(min(1.0, dot))
    s0 = math.sin((1.0 - fraction) * theta) / math.sin(theta)
    s1 = math.sin(fraction * theta) / math.sin(theta)
    return tuple(s0 * a + s1 * b for a, b in zip(q0, q1, strict=False))  # type: ignore[return-value]


def compose(a: Transform, b: Transform) -> Transform:
    """``a * b``: if ``a`` is frame B in frame A and ``b`` is frame C in frame B, the result is
    frame C in frame A."""
    (at, aq), (bt, bq) = a, b
    rt = rotate_vector(aq, bt)
    return ((at[0] + rt[0], at[1] + rt[1], at[2] + rt[2]), normalize(quaternion_multiply(aq, bq)))


def inverse(t: Transform) -> Transform:
    """The transform undoing ``t`` (frame A in frame B when ``t`` is frame B in frame A)."""
    trans, rot = t
    qi = quaternion_inverse(rot)
    r = rotate_vector(qi, trans)
    return ((-r[0], -r[1], -r[2]), qi)


def interpolate(a: Transform, b: Transform, fraction: float) -> Transform:
    """Linear translation, spherical rotation, ``fraction`` in [0, 1] from ``a`` to ``b``."""
    (at, aq), (bt, bq) = a, b
    trans = tuple(x + fraction * (y - x) for x, y in zip(at, bt, strict=False))
    return (trans, quaternion_slerp(aq, bq, fraction))  # type: ignore[return-value]


def transform_point(t: Transform, p: Sequence[float]) -> Vector:
    """Point ``p`` given in the child frame, expressed in the parent frame."""
    trans, rot = t
    r = rotate_vector(rot, p)
    return (r[0] + trans[0], r[1] + trans[1], r[2] + trans[2])


def yaw_from_quaternion(q: Sequence[float]) -> float:
    """Heading about Z: the one angle planar robots (and turtles) care about."""
    return euler_from_quaternion(q)[2]
