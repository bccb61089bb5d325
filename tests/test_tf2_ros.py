"""orchestra.tf.tf2_ros: tf2_ros's Buffer API (TransformStamped in and out) over the tree."""
from __future__ import annotations

import math
import threading
import time

import pytest

from orchestra.node.msg import get_message_class
from orchestra.node.rostime import Duration, Time
from orchestra.tf import buffer as tree_errors
from orchestra.tf import quaternion_from_euler, tf2_ros, yaw_from_quaternion
from orchestra.tf.convert import fill_transform_msg


def stamped(parent, child, stamp, x=0.0, y=0.0, yaw=0.0):
    msg = get_message_class("geometry_msgs/TransformStamped")()
    return fill_transform_msg(msg, (x, y, 0.0), quaternion_from_euler(0, 0, yaw), stamp,
                              child=child, parent=parent)


def xy(t):
    return t.transform.translation.x, t.transform.translation.y


def yaw(t):
    r = t.transform.rotation
    return yaw_from_quaternion((r.x, r.y, r.z, r.w))


def close(a, b, tol=1e-9):
    return all(abs(p - q) <= tol for p, q in zip(a, b, strict=False))


def turtles(buffer, stamp=None):
    stamp = Time(5) if stamp is None else stamp
    buffer.set_transform(stamped("world", "turtle1", stamp, 5.0, 5.0, 0.0))
    buffer.set_transform(stamped("world", "turtle2", stamp, 2.0, 5.0, math.pi / 2))


def test_lookup_transform_returns_a_transform_stamped_of_source_in_target():
    buffer = tf2_ros.Buffer()
    turtles(buffer)
    t = buffer.lookup_transform("turtle2", "turtle1", Time())
    assert t._type == "geometry_msgs/TransformStamped"
    assert (t.header.frame_id, t.child_frame_id) == ("turtle2", "turtle1")
    assert t.header.stamp == Time(5)  # Time() is the latest common time, reported as used
    assert close(xy(t), (0.0, -3.0))
    assert math.isclose(yaw(t), -math.pi / 2)


def test_lookup_at_a_time_interpolates_and_reports_that_time():
    buffer = tf2_ros.Buffer(cache_time=Duration(10))
    buffer.set_transform(stamped("world", "a", Time(10), 0.0, 0.0))
    buffer.set_transform(stamped("world", "a", Time(12), 2.0, 4.0))
    t = buffer.lookup_transform("world", "a", Time(11), Duration(0))
    assert close(xy(t), (1.0, 2.0)) and t.header.stamp == Time(11)


def test_errors_are_orchestra_tf_exceptions_with_tf2_names():
    assert tf2_ros.LookupException is tree_errors.LookupException
    assert issubclass(tf2_ros.InvalidArgumentException, tf2_ros.TransformException)
    buffer = tf2_ros.Buffer()
    turtles(buffer)
    buffer.set_transform(stamped("map", "odom", Time(5)))
    with pytest.raises(tf2_ros.LookupException):
        buffer.lookup_transform("turtle2", "turtle3", Time())
    with pytest.raises(tf2_ros.ConnectivityException):
        buffer.lookup_transform("turtle2", "odom", Time())
    with pytest.raises(tf2_ros.ExtrapolationException):
        buffer.lookup_transform("turtle2", "turtle1", Time(9))
    with pytest.raises(tf2_ros.InvalidArgumentException):
        buffer.lookup_transform("", "turtle1", Time())
    with pytest.raises(tf2_ros.InvalidArgumentException):
        buffer.set_transform(stamped("turtle1", "turtle1", Time(5)))


def test_can_transform_with_and_without_debug_tuple():
    buffer = tf2_ros.Buffer()
    turtles(buffer)
    assert buffer.can_transform("turtle1", "turtle2", Time())
    assert not buffer.can_transform("turtle1", "nowhere", Time())
    ok, error = buffer.can_transform("turtle1", "nowhere", Time(), return_debug_tuple=True)
    assert not ok and "nowhere" in error


def test_lookup_with_timeout_waits_for_the_data():
    buffer = tf2_ros.Buffer()
    buffer.set_transform(stamped("world", "turtle1", Time(5), 1.0, 0.0))
    threading.Timer(0.2, buffer.set_transform,
                    [stamped("world", "turtle2", Time(5), 3.0, 0.0)]).start()
    started = time.monotonic()
    t = buffer.lookup_transform("turtle2", "turtle1", Time(), timeout=Duration(10))
    assert close(xy(t), (-2.0, 0.0))
    assert time.monotonic() - started < 5.0
    with pytest.raises(tf2_ros.LookupException):
        buffer.lookup_transform("turtle2", "turtle9", Time(), timeout=0.1)


def test_static_transforms_hold_at_any_time():
    buffer = tf2_ros.Buffer()
    buffer.set_transform_static(stamped("base_link", "laser", Time(1), 0.2, 0.0))
    buffer.set_transform(stamped("odom", "base_link", Time(100), 1.0, 0.0))
    assert close(xy(buffer.lookup_transform("odom", "laser", Time())), (1.2, 0.0))


def test_lookup_transform_full_travels_in_time_through_a_fixed_frame():
    buffer = tf2_ros.Buffer()
    for stamp, x in ((10, 0.0), (12, 2.0)):
        buffer.set_transform(stamped("world", "turtle1", Time(stamp), x, 0.0))
        buffer.set_transform(stamped("world", "turtle2", Time(stamp), x, 1.0))
    # where turtle1 was at t=10, seen from turtle2 at t=12
    t = buffer.lookup_transform_full("turtle2", Time(12), "turtle1", Time(10), "world")
    assert close(xy(t), (-2.0, -1.0))
    assert buffer.can_transform_full("turtle2", Time(12), "turtle1", Time(10), "world")
    assert not buffer.can_transform_full("turtle2", Time(12), "turtle1", Time(30), "world")


def test_frames_as_string_and_yaml():
    buffer = tf2_ros.Buffer()
    turtles(buffer)
    buffer.set_transform_static(stamped("turtle1", "nose", Time(5), 0.1))
    assert buffer.all_frames_as_string() == (
        "Frame nose exists with parent turtle1.\n"
        "Frame turtle1 exists with parent world.\n"
        "Frame turtle2 exists with parent world.\n")
    import yaml

    frames = yaml.safe_load(buffer.all_frames_as_yaml())
    assert set(frames) == {"nose", "turtle1", "turtle2"}
    assert frames["turtle1"]["parent"] == "world"
    assert frames["turtle1"]["most_recent_transform"] == 5.0


def test_transform_listener_needs_a_buffer():
    with pytest.raises(TypeError):
        tf2_ros.TransformListener(object())


def test_latest_common_time_is_the_newest_stamp_both_chains_share_and_clear_forgets():
    buffer = tf2_ros.Buffer()
    buffer.set_transform(stamped("world", "a", Time(5)), "test")
    buffer.set_transform(stamped("world", "a", Time(9)), "test")
    buffer.set_transform(stamped("world", "b", Time(7)), "test")
    assert buffer.get_latest_common_time("a", "b") == Time(7)
    buffer.clear()
    assert not buffer.can_transform("a", "b", Time())
    with pytest.raises(tf2_ros.LookupException):
        buffer.get_latest_common_time("a", "b")
