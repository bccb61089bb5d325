"""tf.transformations: 4x4 homogeneous matrices, Euler angles in all 24 axis conventions and
quaternions ``[x, y, z, w]``, as numpy arrays like tf's module (names and argument order
are tf's; the code is orchestra's).

Axis conventions are tf's strings: first letter ``s`` (static axes: rotate about the fixed
axes in the order given) or ``r`` (rotating axes), then the three axes, e.g. ``'sxyz'`` (the
default: roll about X, pitch about Y, yaw about Z) or ``'rzyx'``. The quaternion products
come from orchestra.tf.transformations (one place for the quaternion algebra).
"""
from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy

from orchestra.tf import transformations as _q

_EPS = numpy.finfo(float).eps * 4.0
_AXIS = {"x": 0, "y": 1, "z": 2}


def _axes(axes: str) -> tuple[bool, tuple[int, int, int]]:
    """``(static, (first, second, third))`` for a tf axes string."""
    if (not isinstance(axes, str) or len(axes) != 4 or axes[0] not in "sr"
            or any(a not in _AXIS for a in axes[1:])
            or axes[1] == axes[2] or axes[2] == axes[3]):
        raise KeyError(f"unknown Euler axes convention {axes!r}")
    return axes[0] == "s", (_AXIS[axes[1]], _AXIS[axes[2]], _AXIS[axes[3]])


def _axis_quaternion(axis: int, angle: float) -> tuple:
    q = [0.0, 0.0, 0.0, math.cos(angle / 2.0)]
    q[axis] = math.sin(angle / 2.0)
    return tuple(q)


# --- vectors ------------------------------------------------------------------------------------

def vector_norm(data: Any, axis: int | None = None, out: Any = None) -> Any:
    data = numpy.array(data, dtype=numpy.float64, copy=True)
    norm = numpy.sqrt(numpy.sum(data * data, axis=axis))
    if out is not None:
        out[...] = norm
        return None
    return norm


def unit_vector(data: Any, axis: int | None = None, out: Any = None) -> Any:
    data = numpy.array(data, dtype=numpy.float64, copy=True)
    norm = numpy.sqrt(numpy.sum(data * data, axis=axis, keepdims=axis is not None))
    result = data / norm
    if out is not None:
        out[...] = result
        return None
    return result


# --- matrices -----------------------------------------------------------------------------------

def identity_matrix() -> numpy.ndarray:
    return numpy.identity(4)


def translation_matrix(direction: Sequence[float]) -> numpy.ndarray:
    m = numpy.identity(4)
    m[:3, 3] = numpy.asarray(direction, dtype=numpy.float64)[:3]
    return m


def translation_from_matrix(matrix: Any) -> numpy.ndarray:
    return numpy.array(matrix, dtype=numpy.float64, copy=True)[:3, 3].copy()


def rotation_matrix(angle: float, direction: Sequence[float],
                    point: Sequence[float] | None = None) -> numpy.ndarray:
    """Rotation by ``angle`` about the axis ``direction`` through ``point`` (origin)."""
    axis = unit_vector(numpy.asarray(direction, dtype=numpy.float64)[:3])
    q = [*(axis * math.sin(angle / 2.0)), math.cos(angle / 2.0)]
    m = quaternion_matrix(q)
    if point is not None:
        p = numpy.asarray(point, dtype=numpy.float64)[:3]
        m[:3, 3] = p - numpy.dot(m[:3, :3], p)
    return m


def scale_matrix(factor: float, origin: Sequence[float] | None = None,
                 direction: Sequence[float] | None = None) -> numpy.ndarray:
    """Uniform scaling by ``factor`` about ``origin`` (or along ``direction`` only)."""
    if direction is None:
        m = numpy.diag([factor, factor, factor, 1.0])
        if origin is not None:
            m[:3, 3] = numpy.asarray(origin, dtype=numpy.float64)[:3] * (1.0 - factor)
        return m
    d = unit_vector(numpy.asarray(direction, dtype=numpy.float64)[:3])
    m = numpy.identity(4)
    m[:3, :3] -= (1.0 - factor) * numpy.outer(d, d)
    if origin is not None:
        m[:3, 3] = ((1.0 - factor) * numpy.dot(numpy.asarray(origin, dtype=float)[:3], d)) * d
    return m


def concatenate_matrices(*matrices: Any) -> numpy.ndarray:
    m = numpy.identity(4)
    for other in matrices:
        m = numpy.dot(m, other)
    return m


def inverse_matrix(matrix: Any) -> numpy.ndarray:
    return numpy.linalg.inv(matrix)


def is_same_transform(matrix0: Any, matrix1: Any) -> bool:
    a = numpy.array(matrix0, dtype=numpy.float64, copy=True)
    b = numpy.array(matrix1, dtype=numpy.float64, copy=True)
    return bool(numpy.allclose(a / a[3, 3], b / b[3, 3]))


# --- quaternions --------------------------------------------------------------------------------

def quaternion_matrix(quaternion: Any) -> numpy.ndarray:
    """The 4x4 rotation matrix of ``[x, y, z, w]`` (normalised first; zero -> identity)."""
    q = numpy.array(quaternion[:4], dtype=numpy.float64, copy=True)
    n = numpy.dot(q, q)
    if n < _EPS:
        return numpy.identity(4)
    x, y, z, w = q * math.sqrt(2.0 / n)
    return numpy.array([
        [1.0 - y * y - z * z, x * y - z * w, x * z + y * w, 0.0],
        [x * y + z * w, 1.0 - x * x - z * z, y * z - x * w, 0.0],
        [x * z - y * w, y * z + x * w, 1.0 - x * x - y * y, 0.0],
        [0.0, 0.0, 0.0, 1.0]])


def quaternion_from_matrix(matrix: Any) -> numpy.ndarray:
    """``[x, y, z, w]`` of the rotation part of ``matrix`` (the largest of w, x, y, z is
    computed from the diagonal first, for accuracy)."""
    m = numpy.array(matrix, dtype=numpy.float64, copy=False)[:3, :3]
    trace = m[0, 0] + m[1, 1] + m[2, 2]
    if trace > 0.0:
        s = 2.0 * math.sqrt(trace + 1.0)
        q = [(m[2, 1] - m[1, 2]) / s, (m[0, 2] - m[2, 0]) / s, (m[1, 0] - m[0, 1]) / s, s / 4.0]
    else:
        i = int(numpy.argmax([m[0, 0], m[1, 1], m[2, 2]]))
        j, k = (i + 1) % 3, (i + 2) % 3
        s = 2.0 * math.sqrt(1.0 + m[i, i] - m[j, j] - m[k, k])
        q = [0.0, 0.0, 0.0, (m[k, j] - m[j, k]) / s]
        q[i] = s / 4.0
        q[j] = (m[j, i] + m[i, j]) / s
        q[k] = (m[k, i] + m[i, k]) / s
    return numpy.array(q)


def quaternion_about_axis(angle: float, axis: Sequence[float]) -> numpy.ndarray:
    a = numpy.asarray(axis[:3], dtype=numpy.float64)
    n = vector_norm(a)
    if n > _EPS:
        a = a * (math.sin(angle / 2.0) / n)
    return numpy.array([a[0], a[1], a[2], math.cos(angle / 2.0)])


def quaternion_multiply(quaternion1: Sequence[float],
                        quaternion0: Sequence[float]) -> numpy.ndarray:
    """``quaternion1 * quaternion0``: rotate by ``quaternion0`` first."""
    return numpy.array(_q.quaternion_multiply(quaternion1, quaternion0))


def quaternion_conjugate(quaternion: Sequence[float]) -> numpy.ndarray:
    return numpy.array(_q.quaternion_conjugate(quaternion))


def quaternion_inverse(quaternion: Sequence[float]) -> numpy.ndarray:
    return numpy.array(_q.quaternion_inverse(quaternion))


def quaternion_slerp(quat0: Sequence[float], quat1: Sequence[float], fraction: float,
                     spin: int = 0, shortestpath: bool = True) -> numpy.ndarray:
    """Spherical interpolation from ``quat0`` (fraction 0) to ``quat1`` (1), along the short
    arc (``spin`` extra half-turns and ``shortestpath=False`` are tf's options)."""
    if spin == 0 and shortestpath:
        return numpy.array(_q.quaternion_slerp(quat0, quat1, fraction))
    q0 = unit_vector(quat0[:4])
    q1 = unit_vector(quat1[:4])
    d = float(numpy.dot(q0, q1))
    if abs(abs(d) - 1.0) < _EPS:
        return q0
    if shortestpath and d < 0.0:
        d, q1 = -d, -q1
    angle = math.acos(max(-1.0, min(1.0, d))) + spin * math.pi
    if abs(angle) < _EPS:
        return q0
    isin = 1.0 / math.sin(angle)
    return ((math.sin((1.0 - fraction) * angle) * isin) * q0
            + (math.sin(fraction * angle) * isin) * q1)


def random_quaternion(rand: Sequence[float] | None = None) -> numpy.ndarray:
    """A uniformly distributed unit quaternion (``rand``: three numbers in [0, 1))."""
    r = numpy.random.rand(3) if rand is None else numpy.asarray(rand, dtype=float)
    r1, r2 = math.sqrt(1.0 - r[0]), math.sqrt(r[0])
    t1, t2 = 2.0 * math.pi * r[1], 2.0 * math.pi * r[2]
    return numpy.array([math.sin(t1) * r1, math.cos(t1) * r1, math.sin(t2) * r2,
                        math.cos(t2) * r2])


def random_rotation_matrix(rand: Sequence[float] | None = None) -> numpy.ndarray:
    return quaternion_matrix(random_quaternion(rand))


# --- Euler angles -------------------------------------------------------------------------------

def quaternion_from_euler(ai: float, aj: float, ak: float, axes: str = "sxyz") -> numpy.ndarray:
    """The rotation by ``ai``, ``aj``, ``ak`` about ``axes`` (see the module docstring)."""
    static, (i, j, k) = _axes(axes)
    qi, qj, qk = _axis_quaternion(i, ai), _axis_quaternion(j, aj), _axis_quaternion(k, ak)
    if static:   # fixed axes: the first rotation is applied first, so it stands rightmost
        q = _q.quaternion_multiply(qk, _q.quaternion_multiply(qj, qi))
    else:        # rotating axes: each turn is about the already-turned frame
        q = _q.quaternion_multiply(qi, _q.quaternion_multiply(qj, qk))
    return numpy.array(q)


def euler_matrix(ai: float, aj: float, ak: float, axes: str = "sxyz") -> numpy.ndarray:
    return quaternion_matrix(quaternion_from_euler(ai, aj, ak, axes))


def euler_from_matrix(matrix: Any, axes: str = "sxyz") -> tuple[float, float, float]:
    """``(ai, aj, ak)`` with ``euler_matrix(ai, aj, ak, axes)`` equal to ``matrix``'s
    rotation; at gimbal lock the third angle is 0."""
    static, (i, j, k) = _axes(axes)
    m = numpy.array(matrix, dtype=numpy.float64, copy=False)[:3, :3]
    if not static:  # rotating axes are static axes in reverse order with reversed angles
        a, b, c = _static_angles(m, k, j, i)
        return c, b, a
    return _static_angles(m, i, j, k)


def _static_angles(m: numpy.ndarray, i: int, j: int, k: int) -> tuple[float, float, float]:
    """Angles of R = R_k(c) R_j(b) R_i(a) (static axes i, j, k; k may repeat i)."""
    if i != k:  # Tait-Bryan angles: i, j, k all different
        s = 1.0 if (j - i) % 3 == 1 else -1.0  # +1 for a cyclic order (xyz, yzx, zxy)
        cb = math.hypot(m[i, i], m[j, i])
        if cb > _EPS:
            a = math.atan2(s * m[k, j], m[k, k])
            b = math.atan2(-s * m[k, i], cb)
            c = math.atan2(s * m[j, i], m[i, i])
        else:
            a = math.atan2(-s * m[j, k], m[j, j])
            b = math.atan2(-s * m[k, i], cb)
            c = 0.0
        return a, b, c
    # proper Euler angles: R = R_i(c) R_j(b) R_i(a), with l the third axis
    l = 3 - i - j  # noqa: E741
    s = 1.0 if (j - i) % 3 == 1 else -1.0
    sb = math.hypot(m[i, j], m[i, l])
    if sb > _EPS:
        a = math.atan2(m[i, j], s * m[i, l])
        b = math.atan2(sb, m[i, i])
        c = math.atan2(m[j, i], -s * m[l, i])
        if s < 0:  # of the two solutions, tf reports the one with b <= 0 for an odd order
            a, b, c = _wrap(a + math.pi), -b, _wrap(c + math.pi)
    else:
        a = math.atan2(s * m[l, j], m[j, j])
        b = math.atan2(sb, m[i, i])
        c = 0.0
    return a, b, c


def _wrap(angle: float) -> float:
    return math.atan2(math.sin(angle), math.cos(angle))


def euler_from_quaternion(quaternion: Sequence[float], axes: str = "sxyz") -> tuple:
    return euler_from_matrix(quaternion_matrix(quaternion), axes)


# --- compose / decompose --------------------------------------------------------------------------

def compose_matrix(scale: Sequence[float] | None = None, shear: Sequence[float] | None = None,
                   angles: Sequence[float] | None = None,
                   translate: Sequence[float] | None = None,
                   perspective: Sequence[float] | None = None) -> numpy.ndarray:
    """T * R * Z * S (translation, rotation from sxyz ``angles``, shear, scale); the
    perspective row last, as tf's ``compose_matrix``."""
    m = numpy.identity(4)
    if perspective is not None:
        p = numpy.identity(4)
        p[3, :] = perspective[:4]
        m = numpy.dot(m, p)
    if translate is not None:
        m = numpy.dot(m, translation_matrix(translate))
    if angles is not None:
        m = numpy.dot(m, euler_matrix(angles[0], angles[1], angles[2], "sxyz"))
    if shear is not None:
        z = numpy.identity(4)
        z[1, 2], z[0, 2], z[0, 1] = shear[2], shear[1], shear[0]
        m = numpy.dot(m, z)
    if scale is not None:
        m = numpy.dot(m, numpy.diag([scale[0], scale[1], scale[2], 1.0]))
    return m / m[3, 3]


def decompose_matrix(matrix: Any) -> tuple:
    """``(scale, shear, angles, translate, perspective)`` of an affine ``matrix`` (no
    perspective part: that is ``[0, 0, 0, 1]``); ValueError for a singular one."""
    m = numpy.array(matrix, dtype=numpy.float64, copy=True).T
    if abs(m[3, 3]) < _EPS:
        raise ValueError("matrix is singular")
    m /= m[3, 3]
    perspective = numpy.array([0.0, 0.0, 0.0, 1.0])
    if numpy.any(abs(m[:3, 3]) > _EPS):
        raise ValueError("matrices with a perspective part are not decomposed here")
    translate = m[3, :3].copy()
    rows = m[:3, :3].copy()
    scale = numpy.zeros(3)
    shear = [0.0, 0.0, 0.0]
    scale[0] = vector_norm(rows[0])
    rows[0] /= scale[0]
    shear[0] = numpy.dot(rows[0], rows[1])
    rows[1] -= rows[0] * shear[0]
    scale[1] = vector_norm(rows[1])
    rows[1] /= scale[1]
    shear[0] /= scale[1]
    shear[1] = numpy.dot(rows[0], rows[2])
    rows[2] -= rows[0] * shear[1]
    shear[2] = numpy.dot(rows[1], rows[2])
    rows[2] -= rows[1] * shear[2]
    scale[2] = vector_norm(rows[2])
    rows[2] /= scale[2]
    shear[1] /= scale[2]
    shear[2] /= scale[2]
    if numpy.dot(rows[0], numpy.cross(rows[1], rows[2])) < 0:
        scale *= -1
        rows *= -1
    r = numpy.identity(4)
    r[:3, :3] = rows.T
    angles = euler_from_matrix(r, "sxyz")
    return scale, numpy.array(shear), numpy.array(angles), translate, perspective
