"""tf2_ros's Python API over orchestra's transform tree, so tf2 tutorial code ports by changing
only its import:

    from orchestra.tf import tf2_ros
    buffer = tf2_ros.Buffer()
    listener = tf2_ros.TransformListener(buffer)
    t = buffer.lookup_transform("turtle2", "turtle1", node.Time())   # a TransformStamped
    tf2_ros.TransformBroadcaster().sendTransform(t)

A thin layer: ``Buffer`` holds a ``TransformBuffer`` (``buffer.tree``) and only converts between
geometry_msgs/TransformStamped messages and the tree's ``(translation, rotation)`` tuples; the
listener is orchestra.tf's, fed into that tree; the broadcasters are orchestra.tf's (they
already take TransformStamped messages); the exceptions are orchestra.tf's, so an ``except
tf2_ros.LookupException`` catches what the tree raises. Not here: ``Buffer.transform`` (the
tf2_geometry_msgs conversions) and transform authorities (never recorded).
"""
from __future__ import annotations

import sys
from typing import Any

from orchestra.tf import listener as _listener
from orchestra.tf import transformations as tfm
from orchestra.tf.broadcaster import StaticTransformBroadcaster, TransformBroadcaster
from orchestra.tf.buffer import (
    ConnectivityException,
    ExtrapolationException,
    LookupException,
    TransformBuffer,
    TransformException,
)
from orchestra.tf.convert import fill_transform_msg, to_sec, transform_from_msg
from orchestra.tf.transformations import Transform

__all__ = [
    "Buffer", "TransformListener", "TransformBroadcaster", "StaticTransformBroadcaster",
    "TransformException", "LookupException", "ConnectivityException",
    "ExtrapolationException", "InvalidArgumentException", "TimeoutException",
]

DEFAULT_CACHE_TIME = 10.0


class InvalidArgumentException(TransformException):
    """An empty frame id or a transform the tree refuses (a frame its own parent, a zero
    quaternion)."""


class TimeoutException(TransformException):
    """Exported for ``except`` clauses written for tf2_ros; like tf2_ros's Python Buffer, a
    lookup that times out raises the lookup's own error instead."""


def _is_shutdown() -> bool:
    # the node runtime is not imported for this: a Buffer is usable without any node
    runtime = sys.modules.get("orchestra.node.runtime")
    return bool(runtime is not None and runtime.is_shutdown())


def _check_frames(**frames: str) -> None:
    for argument, frame in frames.items():
        if not frame or not frame.strip("/"):
            raise InvalidArgumentException(
                f"invalid argument passed to lookup_transform argument {argument}: "
                "frame ids cannot be empty")


def _transform_stamped(target: str, source: str, stamp: float, transform: Transform) -> Any:
    from orchestra.node.msg import get_message_class
    from orchestra.node.rostime import Time

    msg = get_message_class("geometry_msgs/TransformStamped")()
    return fill_transform_msg(msg, transform[0], transform[1], Time.from_sec(stamp),
                              child=source, parent=target)


class Buffer:
    """tf2_ros.Buffer: stores transforms (fed by a ``TransformListener`` or ``set_transform``)
    and answers lookups with geometry_msgs/TransformStamped messages. Times are ROS Times,
    Durations or float seconds; time 0 (``Time()``) means the latest common time."""

    def __init__(self, cache_time: Any = None, debug: bool = True):
        seconds = to_sec(cache_time) if cache_time is not None else DEFAULT_CACHE_TIME
        self.tree = TransformBuffer(cache_time=seconds)

    # --- writing -----------------------------------------------------------------------------

    def set_transform(self, transform: Any, authority: str = "default_authority") -> None:
        """Store a TransformStamped (``authority`` is accepted and ignored)."""
        self._set(transform, static=False)

    def set_transform_static(self, transform: Any, authority: str = "default_authority") -> None:
        self._set(transform, static=True)

    def _set(self, transform: Any, static: bool) -> None:
        parent, child, stamp, values = transform_from_msg(transform)
        try:
            self.tree.set_transform(parent, child, stamp, values, static=static)
        except ValueError as exc:
            raise InvalidArgumentException(f"{parent} -> {child}: {exc}") from None

    # --- lookups -----------------------------------------------------------------------------

    def _wait(self, target: str, source: str, stamp: float, timeout: Any) -> None:
        """Block up to ``timeout`` for the lookup to succeed; then its error is raised."""
        if timeout is not None and to_sec(timeout) > 0:
            self.tree.wait_for_transform(target, source, stamp, to_sec(timeout),
                                         is_shutdown=_is_shutdown)

    def lookup_transform(self, target_frame: str, source_frame: str, time: Any,
                         timeout: Any = None) -> Any:
        """The pose of ``source_frame`` in ``target_frame`` at ``time`` (header.frame_id is the
        target, child_frame_id the source, the stamp the time actually used), waiting up to
        ``timeout`` for the data."""
        _check_frames(target_frame=target_frame, source_frame=source_frame)
        stamp = to_sec(time)
        self._wait(target_frame, source_frame, stamp, timeout)
        transform, used = self.tree.lookup(target_frame, source_frame, stamp)
        return _transform_stamped(target_frame, source_frame, used, transform)

    def lookup_transform_full(self, target_frame: str, target_time: Any, source_frame: str,
                              source_time: Any, fixed_frame: str, timeout: Any = None) -> Any:
        """Time travel: ``source_frame`` at ``source_time`` seen from ``target_frame`` at
        ``target_time``, through ``fixed_frame`` (assumed not to move between the two)."""
        _check_frames(target_frame=target_frame, source_frame=source_frame,
                      fixed_frame=fixed_frame)
        t_target, t_source = to_sec(target_time), to_sec(source_time)
        self._wait(target_frame, fixed_frame, t_target, timeout)
        self._wait(fixed_frame, source_frame, t_source, timeout)
        target_in_fixed, used = self.tree.lookup(target_frame, fixed_frame, t_target)
        fixed_in_source, _ = self.tree.lookup(fixed_frame, source_frame, t_source)
        return _transform_stamped(target_frame, source_frame, used,
                                  tfm.compose(target_in_fixed, fixed_in_source))

    def can_transform(self, target_frame: str, source_frame: str, time: Any,
                      timeout: Any = None, return_debug_tuple: bool = False) -> Any:
        """Whether ``lookup_transform`` would succeed (waiting up to ``timeout``); with
        ``return_debug_tuple``, ``(ok, error text)``."""
        return self._can(return_debug_tuple, self.lookup_transform, target_frame,
                         source_frame, time, timeout)

    def can_transform_full(self, target_frame: str, target_time: Any, source_frame: str,
                           source_time: Any, fixed_frame: str, timeout: Any = None,
                           return_debug_tuple: bool = False) -> Any:
        return self._can(return_debug_tuple, self.lookup_transform_full, target_frame,
                         target_time, source_frame, source_time, fixed_frame, timeout)

    @staticmethod
    def _can(debug: bool, lookup, *args: Any) -> Any:
        try:
            lookup(*args)
        except TransformException as exc:
            return (False, str(exc)) if debug else False
        return (True, "") if debug else True

    def get_latest_common_time(self, target_frame: str, source_frame: str) -> Any:
        """The newest time both frames' chains have data for (a ROS Time; 0 for a static
        chain), tf2's ``getLatestCommonTime``."""
        from orchestra.node.rostime import Time

        _check_frames(target_frame=target_frame, source_frame=source_frame)
        _, used = self.tree.lookup(target_frame, source_frame, 0.0)
        return Time.from_sec(used)

    def clear(self) -> None:
        """Forget every transform (a listener keeps filling the same buffer)."""
        self.tree.clear()

    # --- introspection -----------------------------------------------------------------------

    def all_frames_as_string(self) -> str:
        """One line per frame that has a parent, as tf2's ``allFramesAsString``."""
        return "".join(f"Frame {child} exists with parent {parent}.\n"
                       for child, parent in sorted(self.tree.parents().items()))

    def all_frames_as_yaml(self) -> str:
        """Per frame: parent, rate, newest/oldest stamps and buffer length (tf2's
        ``allFramesAsYAML`` keys; the broadcaster is not recorded)."""
        lines = []
        for child, info in sorted(self.tree.edge_info().items()):
            length = info["newest"] - info["oldest"]
            rate = (info["samples"] - 1) / length if length > 0 else 10000.0
            if info["static"]:
                rate, length, newest, oldest = 10000.0, 0.0, 0.0, 0.0
            else:
                newest, oldest = info["newest"], info["oldest"]
            lines += [f"{child}: ", f"  parent: '{info['parent']}'",
                      "  broadcaster: 'unknown_publisher'", f"  rate: {rate:.3f}",
                      f"  most_recent_transform: {newest:.6f}",
                      f"  oldest_transform: {oldest:.6f}", f"  buffer_length: {length:.3f}"]
        return "\n".join(lines) + ("\n" if lines else "")


class TransformListener(_listener.TransformListener):
    """tf2_ros.TransformListener(buffer): subscribes /tf and /tf_static into ``buffer`` for as
    long as the node lives. ``queue_size``, ``buff_size`` and ``tcp_nodelay`` are accepted
    for tf2_ros's signature and ignored."""

    def __init__(self, buffer: Buffer, queue_size: Any = None, buff_size: int = 65536,
                 tcp_nodelay: bool = False):
        if not isinstance(buffer, Buffer):
            raise TypeError("tf2_ros.TransformListener needs a tf2_ros.Buffer")
        super().__init__(buffer.tree)
