"""tf2_ros for orchestra's ROS 1 layer: orchestra.tf.tf2_ros (Buffer, TransformListener,
TransformBroadcaster, StaticTransformBroadcaster and tf2's exceptions) under its own name.
The exceptions are the ones tf raises too, as in ROS where both come from tf2."""
from orchestra.tf.tf2_ros import (
                                  Buffer,
                                  ConnectivityException,
                                  ExtrapolationException,
                                  InvalidArgumentException,
                                  LookupException,
                                  StaticTransformBroadcaster,
                                  TimeoutException,
                                  TransformBroadcaster,
                                  TransformException,
                                  TransformListener,
)

__all__ = ["Buffer", "ConnectivityException", "ExtrapolationException",
           "InvalidArgumentException", "LookupException", "StaticTransformBroadcaster",
           "TimeoutException", "TransformBroadcaster", "TransformException",
           "TransformListener"]
