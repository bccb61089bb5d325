"""Between geometry_msgs/TransformStamped messages and the buffer's (translation, rotation).

Kept apart from the broadcaster/listener so the conversion rules (leading slashes, time as
float seconds, accepting rospy-style Time or plain numbers) are testable without a master.
"""
from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from orchestra.tf.transformations import Transform


def to_sec(stamp: Any) -> float:
    """Float seconds from a node-runtime Time, a (secs, nsecs)-shaped object, a number or None."""
    if stamp is None:
        return 0.0
    if isinstance(stamp, (int, float)):
        return float(stamp)
    if hasattr(stamp, "to_sec"):
        return float(stamp.to_sec())
    if hasattr(stamp, "secs"):
        return stamp.secs + stamp.nsecs * 1e-9
    if hasattr(stamp, "sec"):  # ROS 2 / rosbags shape
        return stamp.sec + stamp.nanosec * 1e-9
    raise TypeError(f"cannot read a time from {stamp!r}")


def transform_from_msg(msg: Any) -> tuple[str, str, float, Transform]:
    """(parent, child, stamp seconds, transform) of a geometry_msgs/TransformStamped."""
    t, r = msg.transform.translation, msg.transform.rotation
    return (msg.header.frame_id, msg.child_frame_id, to_sec(msg.header.stamp),
            ((t.x, t.y, t.z), (r.x, r.y, r.z, r.w)))


def fill_transform_msg(msg: Any, translation: Sequence[float], rotation: Sequence[float],
                       stamp: Any, child: str, parent: str) -> Any:
    """Fill a constructed TransformStamped in place (the message class comes from the runtime)."""
    msg.header.stamp = stamp
    msg.header.frame_id = parent
    msg.child_frame_id = child
    tr, ro = msg.transform.translation, msg.transform.rotation
    tr.x, tr.y, tr.z = (float(c) for c in translation)
    ro.x, ro.y, ro.z, ro.w = (float(c) for c in rotation)
    return msg
