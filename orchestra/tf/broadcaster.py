"""Publishing transforms: /tf for moving frames, latched /tf_static for fixed ones.

Both tf1's call shape (``sendTransform(translation, rotation, time, child, parent)``) and
tf2_ros's (``sendTransform(transform_stamped or list)``) are accepted, because the tutorials
users copy from use both.
"""
from __future__ import annotations

import threading
from collections.abc import Iterable, Sequence
from typing import Any

from orchestra.tf.convert import fill_transform_msg

TF_TOPIC = "/tf"
TF_STATIC_TOPIC = "/tf_static"


def _node():
    # imported late: the pure parts of orchestra.tf must not need the node runtime
    import orchestra.node as node
    from orchestra.node.msg import get_message_class
    return node, get_message_class


def make_transform(translation: Sequence[float], rotation: Sequence[float], time: Any,
                   child: str, parent: str) -> Any:
    """A geometry_msgs/TransformStamped for these values (``time`` None → now)."""
    node, get_message_class = _node()
    msg = get_message_class("geometry_msgs/TransformStamped")()
    return fill_transform_msg(msg, translation, rotation,
                              node.Time.now() if time is None else time, child, parent)


class TransformBroadcaster:
    """Sends moving frames on /tf (the tf/tf2 ``TransformBroadcaster``)."""

    topic = TF_TOPIC
    latch = False

    def __init__(self, queue_size: int = 100):
        node, get_message_class = _node()
        self._tf_message = get_message_class("tf2_msgs/TFMessage")
        self._pub = node.Publisher(self.topic, self._tf_message, queue_size=queue_size,
                                   latch=self.latch)

    def sendTransform(self, *args: Any) -> None:  # noqa: N802 - tf's name
        """``(translation, rotation, time, child, parent)`` or ``(TransformStamped | list)``."""
        if len(args) == 5:
            self.send_transforms([make_transform(*args)])
        elif len(args) == 1:
            one = args[0]
            self.send_transforms(list(one) if isinstance(one, (list, tuple)) else [one])
        else:
            raise TypeError("sendTransform takes (translation, rotation, time, child, parent) "
                            "or a TransformStamped / list of them")

    send_transform = sendTransform

    def send_transforms(self, transforms: Iterable[Any]) -> None:
        self._pub.publish(self._tf_message(transforms=list(transforms)))


class StaticTransformBroadcaster(TransformBroadcaster):
    """Latched /tf_static: every frame sent so far is re-published as one message, so a late
    listener gets the whole static tree (tf2_ros behaviour)."""

    topic = TF_STATIC_TOPIC
    latch = True

    def __init__(self) -> None:
        super().__init__(queue_size=100)
        self._static: dict[str, Any] = {}
        self._lock = threading.Lock()

    def send_transforms(self, transforms: Iterable[Any]) -> None:
        with self._lock:
            for t in transforms:
                self._static[t.child_frame_id] = t
            everything = list(self._static.values())
        super().send_transforms(everything)
