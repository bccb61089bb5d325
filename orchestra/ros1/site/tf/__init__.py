"""tf (ROS 1's Python tf) for orchestra's ROS 1 layer, over orchestra.tf's tree and topics.

``Transformer`` is tf's buffer API (``setTransform``, ``lookupTransform`` returning
``([x, y, z], [x, y, z, w])``, ``canTransform``, ``waitForTransform``, ``transformPoint``...)
on an ``orchestra.tf.TransformBuffer``; ``TransformListener`` is a Transformer fed from /tf
and /tf_static by orchestra.tf's listener; ``TransformBroadcaster`` is orchestra.tf's.
``tf.Exception`` and its three subclasses are orchestra.tf's, so the tutorials' ``except
(tf.LookupException, ...)`` catches what the tree raises. ``tf.transformations`` (numpy) is
imported on first use.
"""
from __future__ import annotations

import importlib
from typing import Any

from orchestra.tf import broadcaster as _broadcaster
from orchestra.tf import listener as _listener
from orchestra.tf import transformations as _tfm
from orchestra.tf.buffer import (
    ConnectivityException,
    ExtrapolationException,
    LookupException,
    TransformBuffer,
)
from orchestra.tf.buffer import TransformException as Exception  # noqa: A001 - tf's name
from orchestra.tf.convert import to_sec, transform_from_msg

__all__ = ["ConnectivityException", "Exception", "ExtrapolationException", "LookupException",
           "TransformBroadcaster", "TransformListener", "Transformer", "transformations"]

#: tf's ``Transformer(interpolate, cache_time)`` default, in seconds
DEFAULT_CACHE_TIME = 10.0


def __getattr__(name: str) -> Any:
    if name == "transformations":  # numpy: only for scripts that use it
        return importlib.import_module(f"{__name__}.transformations")
    raise AttributeError(f"module 'tf' has no attribute {name!r}")


def _rospy_time(seconds: float) -> Any:
    from orchestra.node.rostime import Time
    return Time.from_sec(seconds)


class Transformer:
    """tf.Transformer: a transform tree with tf1's method names."""

    def __init__(self, interpolate: bool = True, cache_time: Any = None):
        seconds = DEFAULT_CACHE_TIME if cache_time is None else to_sec(cache_time)
        self._buffer = TransformBuffer(cache_time=seconds)

    def setTransform(self, transform: Any, authority: str = "default_authority") -> None:  # noqa: N802
        """Store a geometry_msgs/TransformStamped (``authority`` is not recorded)."""
        parent, child, stamp, values = transform_from_msg(transform)
        self._buffer.set_transform(parent, child, stamp, values)

    def clear(self) -> None:
        self._buffer.clear()

    def frameExists(self, frame_id: str) -> bool:  # noqa: N802
        return frame_id.lstrip("/") in self._buffer.frames()

    def getFrameStrings(self) -> list[str]:  # noqa: N802
        return self._buffer.frames()

    def allFramesAsString(self) -> str:  # noqa: N802
        return "".join(f"Frame {child} exists with parent {parent}.\n"
                       for child, parent in sorted(self._buffer.parents().items()))

    def lookupTransform(self, target_frame: str, source_frame: str, time: Any) -> tuple:  # noqa: N802
        """``(translation, rotation)`` lists: the pose of ``source_frame`` in
        ``target_frame`` at ``time`` (``rospy.Time(0)``: the latest common time)."""
        (trans, rot), _ = self._buffer.lookup(target_frame, source_frame, to_sec(time))
        return list(trans), list(rot)

    def lookupTransformFull(self, target_frame: str, target_time: Any, source_frame: str,  # noqa: N802
                            source_time: Any, fixed_frame: str) -> tuple:
        """Time travel through ``fixed_frame`` (tf's lookupTransformFull)."""
        target_in_fixed, _ = self._buffer.lookup(target_frame, fixed_frame, to_sec(target_time))
        fixed_in_source, _ = self._buffer.lookup(fixed_frame, source_frame, to_sec(source_time))
        trans, rot = _tfm.compose(target_in_fixed, fixed_in_source)
        return list(trans), list(rot)

    def canTransform(self, target_frame: str, source_frame: str, time: Any) -> bool:  # noqa: N802
        return self._buffer.can_transform(target_frame, source_frame, to_sec(time))

    def canTransformFull(self, target_frame: str, target_time: Any, source_frame: str,  # noqa: N802
                         source_time: Any, fixed_frame: str) -> bool:
        return (self._buffer.can_transform(target_frame, fixed_frame, to_sec(target_time))
                and self._buffer.can_transform(fixed_frame, source_frame, to_sec(source_time)))

    def waitForTransformFull(self, target_frame: str, target_time: Any, source_frame: str,  # noqa: N802
                             source_time: Any, fixed_frame: str, timeout: Any,
                             polling_sleep_duration: Any = None) -> None:
        self.waitForTransform(target_frame, fixed_frame, target_time, timeout)
        self.waitForTransform(fixed_frame, source_frame, source_time, timeout)

    def getTFPrefix(self) -> str:  # noqa: N802
        """tf_prefix was dropped with tf2; always empty, as in tf on noetic."""
        return ""

    def waitForTransform(self, target_frame: str, source_frame: str, time: Any,  # noqa: N802
                         timeout: Any, polling_sleep_duration: Any = None) -> None:
        """Block until the transform is available; ``tf.Exception`` after ``timeout``."""
        self._buffer.wait_for_transform(target_frame, source_frame, to_sec(time),
                                        to_sec(timeout), is_shutdown=_is_shutdown)

    def getLatestCommonTime(self, source_frame: str, dest_frame: str) -> Any:  # noqa: N802
        """The newest time both frames' chains have data for (a ``rospy.Time``)."""
        _, used = self._buffer.lookup(dest_frame, source_frame, 0.0)
        return _rospy_time(used)

    # --- transforming stamped geometry_msgs ---------------------------------------------------

    def _transform_to(self, target_frame: str, header: Any) -> tuple:
        return self._buffer.lookup(target_frame, header.frame_id, to_sec(header.stamp))[0]

    @staticmethod
    def _stamped(msg: Any, target_frame: str) -> Any:
        out = type(msg)()
        out.header.stamp = msg.header.stamp
        out.header.frame_id = target_frame
        return out

    def transformPoint(self, target_frame: str, ps: Any) -> Any:  # noqa: N802
        """A geometry_msgs/PointStamped expressed in ``target_frame``."""
        t = self._transform_to(target_frame, ps.header)
        out = self._stamped(ps, target_frame)
        out.point.x, out.point.y, out.point.z = _tfm.transform_point(
            t, (ps.point.x, ps.point.y, ps.point.z))
        return out

    def transformVector3(self, target_frame: str, v3s: Any) -> Any:  # noqa: N802
        """A geometry_msgs/Vector3Stamped in ``target_frame`` (rotated, not translated)."""
        t = self._transform_to(target_frame, v3s.header)
        out = self._stamped(v3s, target_frame)
        out.vector.x, out.vector.y, out.vector.z = _tfm.rotate_vector(
            t[1], (v3s.vector.x, v3s.vector.y, v3s.vector.z))
        return out

    def transformQuaternion(self, target_frame: str, ps: Any) -> Any:  # noqa: N802
        """A geometry_msgs/QuaternionStamped in ``target_frame``."""
        t = self._transform_to(target_frame, ps.header)
        out = self._stamped(ps, target_frame)
        q = ps.quaternion
        out.quaternion.x, out.quaternion.y, out.quaternion.z, out.quaternion.w = \
            _tfm.quaternion_multiply(t[1], (q.x, q.y, q.z, q.w))
        return out

    def transformPose(self, target_frame: str, ps: Any) -> Any:  # noqa: N802
        """A geometry_msgs/PoseStamped in ``target_frame``."""
        t = self._transform_to(target_frame, ps.header)
        out = self._stamped(ps, target_frame)
        p, q = ps.pose.position, ps.pose.orientation
        pos, rot = _tfm.compose(t, ((p.x, p.y, p.z), (q.x, q.y, q.z, q.w)))
        out.pose.position.x, out.pose.position.y, out.pose.position.z = pos
        o = out.pose.orientation
        o.x, o.y, o.z, o.w = rot
        return out


def _is_shutdown() -> bool:
    from orchestra.node.runtime import is_shutdown
    return is_shutdown()


class TransformListener(Transformer):
    """tf.TransformListener(): a Transformer kept up to date from /tf and /tf_static for as
    long as the node lives (needs ``rospy.init_node`` first, as in tf)."""

    def __init__(self, interpolate: bool = True, cache_time: Any = None):
        super().__init__(interpolate, cache_time)
        self._feed = _listener.TransformListener(self._buffer)


class TransformBroadcaster(_broadcaster.TransformBroadcaster):
    """tf.TransformBroadcaster: ``sendTransform(translation, rotation, time, child, parent)``;
    ``sendTransformMessage(transform_stamped)``."""

    def sendTransform(self, translation: Any, rotation: Any, time: Any, child: str,  # noqa: N802
                      parent: str) -> None:
        """Send ``child``'s pose in ``parent`` at ``time`` on /tf."""
        super().sendTransform(translation, rotation, time, child, parent)

    def sendTransformMessage(self, transform: Any) -> None:  # noqa: N802
        """Send a geometry_msgs/TransformStamped on /tf."""
        super().sendTransform(transform)

