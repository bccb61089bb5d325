"""The transform tree: path lookups, time interpolation, latest-common-time, errors."""
from __future__ import annotations

import math

import pytest

from orchestra.tf import transformations as tfm
from orchestra.tf.buffer import (
    ConnectivityException,
    ExtrapolationException,
    LookupException,
    TransformBuffer,
)
from orchestra.tf.convert import fill_transform_msg, to_sec, transform_from_msg


def pose2d(x, y, yaw):
    return ((x, y, 0.0), tfm.quaternion_from_euler(0, 0, yaw))


def close(a, b, tol=1e-9):
    return all(abs(x - y) <= tol for x, y in zip(a, b, strict=False))


def turtles(buf, t=1.0):
    buf.set_transform("world", "turtle1", t, pose2d(5.0, 5.0, 0.0))
    buf.set_transform("/world", "/turtle2", t, pose2d(2.0, 5.0, math.pi / 2))


def test_lookup_between_siblings_gives_source_in_target_frame():
    buf = TransformBuffer()
    turtles(buf)
    (trans, rot), _ = buf.lookup("turtle2", "turtle1")
    # turtle1 is 3 m along world x; turtle2 faces world +y, so that is its -y
    assert close(trans, (0.0, -3.0, 0.0))
    assert math.isclose(tfm.yaw_from_quaternion(rot), -math.pi / 2, abs_tol=1e-9)


def test_leading_slash_frames_are_the_same_frame():
    buf = TransformBuffer()
    turtles(buf)
    assert buf.frames() == ["turtle1", "turtle2", "world"]
    assert close(buf.lookup("/world", "turtle1")[0][0], (5.0, 5.0, 0.0))


def test_lookup_time_zero_uses_latest_common_time_of_the_path():
    buf = TransformBuffer()
    buf.set_transform("world", "a", 1.0, pose2d(0, 0, 0))
    buf.set_transform("world", "a", 2.0, pose2d(1, 0, 0))
    buf.set_transform("world", "b", 1.5, pose2d(0, 0, 0))
    (trans, _), stamp = buf.lookup("b", "a", 0)
    assert stamp == 1.5
    assert close(trans, (0.5, 0.0, 0.0))


def test_lookup_interpolates_between_samples():
    buf = TransformBuffer()
    buf.set_transform("world", "a", 10.0, pose2d(0, 0, 0))
    buf.set_transform("world", "a", 12.0, pose2d(2, 4, math.pi / 2))
    (trans, rot), _ = buf.lookup("world", "a", 11.0)
    assert close(trans, (1.0, 2.0, 0.0))
    assert math.isclose(tfm.yaw_from_quaternion(rot), math.pi / 4, abs_tol=1e-9)


def test_lookup_outside_history_is_extrapolation_unless_within_tolerance():
    buf = TransformBuffer()
    buf.set_transform("world", "a", 10.0, pose2d(0, 0, 0))
    buf.set_transform("world", "a", 11.0, pose2d(1, 0, 0))
    with pytest.raises(ExtrapolationException):
        buf.lookup("world", "a", 11.5)
    tolerant = TransformBuffer(tolerance=1.0)
    tolerant.set_transform("world", "a", 10.0, pose2d(0, 0, 0))
    assert close(tolerant.lookup("world", "a", 10.5)[0][0], (0, 0, 0))


def test_static_edge_answers_at_any_time():
    buf = TransformBuffer()
    buf.set_transform("base_link", "laser", 0.0, pose2d(0.1, 0, 0), static=True)
    buf.set_transform("odom", "base_link", 5.0, pose2d(1, 0, 0))
    (trans, _), stamp = buf.lookup("odom", "laser", 0)
    assert stamp == 5.0
    assert close(trans, (1.1, 0, 0))


def test_chain_of_three_edges_composes_rotations_and_translations():
    buf = TransformBuffer()
    buf.set_transform("map", "odom", 1.0, pose2d(1, 0, math.pi / 2))
    buf.set_transform("odom", "base", 1.0, pose2d(1, 0, 0))
    buf.set_transform("base", "laser", 1.0, pose2d(0, 1, 0))
    (trans, _), _ = buf.lookup("map", "laser")
    assert close(trans, (0.0, 1.0, 0.0))
    (back, _), _ = buf.lookup("laser", "map")
    assert close(tfm.transform_point(((0.0, 1.0, 0.0), tfm.quaternion_from_euler(0, 0, math.pi / 2)),
                                     back), (0, 0, 0))


def test_unknown_frame_is_lookup_error_and_separate_trees_are_connectivity_error():
    buf = TransformBuffer()
    turtles(buf)
    buf.set_transform("elsewhere", "thing", 1.0, pose2d(0, 0, 0))
    with pytest.raises(LookupException):
        buf.lookup("world", "nowhere")
    with pytest.raises(ConnectivityException):
        buf.lookup("world", "thing")
    assert not buf.can_transform("world", "thing")
    assert buf.can_transform("world", "turtle2")


def test_reparenting_a_frame_replaces_its_old_edge():
    buf = TransformBuffer()
    buf.set_transform("a", "c", 1.0, pose2d(1, 0, 0))
    buf.set_transform("b", "c", 1.0, pose2d(2, 0, 0))
    assert buf.parents() == {"c": "b"}
    with pytest.raises(ConnectivityException):
        buf.lookup("a", "c")


def test_history_older_than_cache_time_is_dropped():
    buf = TransformBuffer(cache_time=2.0)
    for t in range(10):
        buf.set_transform("world", "a", float(t), pose2d(t, 0, 0))
    info = buf.edge_info()["a"]
    assert info["oldest"] == 7.0 and info["newest"] == 9.0


def test_wait_for_transform_times_out_with_the_lookup_error():
    buf = TransformBuffer()
    with pytest.raises(LookupException):
        buf.wait_for_transform("world", "a", 0.0, timeout=0.05)


class _Obj:
    def __init__(self, **kw):
        self.__dict__.update(kw)


def _msg():
    vec = _Obj(x=0.0, y=0.0, z=0.0)
    rot = _Obj(x=0.0, y=0.0, z=0.0, w=1.0)
    return _Obj(header=_Obj(stamp=None, frame_id=""), child_frame_id="",
                transform=_Obj(translation=vec, rotation=rot))


def test_transform_message_roundtrip_keeps_frames_time_and_values():
    msg = fill_transform_msg(_msg(), (1, 2, 3), (0, 0, 1, 0), 4.5, "child", "parent")
    parent, child, stamp, (trans, rot) = transform_from_msg(msg)
    assert (parent, child, stamp, trans, rot) == ("parent", "child", 4.5, (1, 2, 3), (0, 0, 1, 0))


def test_to_sec_reads_secs_nsecs_shaped_times():
    assert to_sec(_Obj(secs=3, nsecs=500_000_000)) == 3.5
    assert to_sec(None) == 0.0
