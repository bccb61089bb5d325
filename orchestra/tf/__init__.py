"""tf for orchestra: a transform tree fed by /tf and /tf_static, with tf's call shapes.

    from orchestra.tf import TransformBroadcaster, TransformListener
    TransformBroadcaster().sendTransform((x, y, 0), q, Time.now(), "turtle1", "world")
    trans, rot = TransformListener().lookupTransform("turtle2", "turtle1", Time(0))

tf2_ros's API (a ``Buffer`` whose lookups return TransformStamped messages, fed by
``TransformListener(buffer)``) is ``orchestra.tf.tf2_ros``, a thin layer over the same parts.

The math (``transformations``) and the tree (``buffer``) are pure; the broadcaster and
listener import the node runtime only when constructed, so importing this package is cheap.
"""
from orchestra.tf.broadcaster import StaticTransformBroadcaster, TransformBroadcaster, make_transform
from orchestra.tf.buffer import (
                                      ConnectivityException,
                                      ExtrapolationException,
                                      LookupException,
                                      TransformBuffer,
                                      TransformException,
)
from orchestra.tf.listener import TransformListener
from orchestra.tf.transformations import (
                                      compose,
                                      euler_from_quaternion,
                                      inverse,
                                      quaternion_from_euler,
                                      quaternion_multiply,
                                      rotate_vector,
                                      transform_point,
                                      yaw_from_quaternion,
)

__all__ = [
    "TransformBroadcaster", "StaticTransformBroadcaster", "TransformListener",
    "TransformBuffer", "TransformException", "LookupException", "ConnectivityException",
    "ExtrapolationException", "quaternion_from_euler", "euler_from_quaternion",
    "quaternion_multiply", "rotate_vector", "compose", "inverse", "transform_point",
    "yaw_from_quaternion", "make_transform",
]

