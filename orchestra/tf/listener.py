"""Receiving transforms: subscribe /tf and /tf_static into a ``TransformBuffer``.

Offers tf1's camelCase names (``lookupTransform`` returning ``(translation, quaternion)``,
``waitForTransform``, ``canTransform``) and snake_case twins, so tutorial code ports by
changing only its imports.
"""
from __future__ import annotations

from typing import Any

from orchestra.tf.broadcaster import TF_STATIC_TOPIC, TF_TOPIC
from orchestra.tf.buffer import TransformBuffer
from orchestra.tf.convert import to_sec, transform_from_msg
from orchestra.tf.transformations import Transform


class TransformListener:
    """Fills a buffer from /tf and /tf_static for as long as the node lives."""

    def __init__(self, buffer: TransformBuffer | None = None, cache_time: float = 10.0):
        import orchestra.node as node
        from orchestra.node.msg import get_message_class
        self._node = node
        self.buffer = buffer if buffer is not None else TransformBuffer(cache_time=cache_time)
        tf_message = get_message_class("tf2_msgs/TFMessage")
        self._subs = [
            node.Subscriber(TF_TOPIC, tf_message, self._on_tf, queue_size=100),
            node.Subscriber(TF_STATIC_TOPIC, tf_message, self._on_tf_static, queue_size=100),
        ]

    def _store(self, msg: Any, static: bool) -> None:
        for t in msg.transforms:
            parent, child, stamp, transform = transform_from_msg(t)
            try:
                self.buffer.set_transform(parent, child, stamp, transform, static=static)
            except ValueError as exc:
                self._node.logwarn("ignoring transform %s -> %s: %s", parent, child, exc)

    def _on_tf(self, msg: Any) -> None:
        self._store(msg, static=False)

    def _on_tf_static(self, msg: Any) -> None:
        self._store(msg, static=True)

    def lookup_transform(self, target: str, source: str, time: Any = None,
                         timeout: Any = None) -> Transform:
        """``(translation, quaternion)``: pose of ``source`` in ``target`` (time 0/None = latest).
        With a ``timeout`` (seconds or Duration) wait that long for it, as tf2_ros does."""
        if timeout is not None and to_sec(timeout) > 0:
            return self.wait_for_transform(target, source, time, timeout)
        return self.buffer.lookup(target, source, to_sec(time))[0]

    lookupTransform = lookup_transform  # noqa: N815 - tf's name

    def can_transform(self, target: str, source: str, time: Any = None) -> bool:
        return self.buffer.can_transform(target, source, to_sec(time))

    canTransform = can_transform  # noqa: N815

    def wait_for_transform(self, target: str, source: str, time: Any = None,
                           timeout: Any = 1.0) -> Transform:
        """Block until available; raises the lookup's ``TransformException`` after ``timeout``
        (seconds or a Duration)."""
        return self.buffer.wait_for_transform(target, source, to_sec(time), to_sec(timeout),
                                              is_shutdown=self._node.is_shutdown)

    waitForTransform = wait_for_transform  # noqa: N815

    def frames(self) -> list[str]:
        return self.buffer.frames()

    getFrameStrings = frames  # noqa: N815

    def unregister(self) -> None:
        for sub in self._subs:
            sub.unregister()

