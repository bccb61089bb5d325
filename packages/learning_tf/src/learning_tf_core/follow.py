"""Pure rules of the tf tutorial, testable without a master.

The follower looks up turtle1 in turtle2's frame and steers with the tutorial's gains:
angular = 4.0 * atan2(y, x) (turn towards it), linear = 0.5 * sqrt(x^2 + y^2) (go faster when
far). A turtle's pose becomes the transform world -> turtle: (x, y, 0), yaw = theta.
"""
from __future__ import annotations

import math

from orchestra.tf.transformations import Quaternion, Vector, quaternion_from_euler

ANGULAR_GAIN = 4.0
LINEAR_GAIN = 0.5
WORLD_FRAME = "world"


def follow_command(x: float, y: float) -> tuple[float, float]:
    """(linear, angular) towards a target at (x, y) in the follower's own frame."""
    return LINEAR_GAIN * math.sqrt(x * x + y * y), ANGULAR_GAIN * math.atan2(y, x)


def pose_to_transform(x: float, y: float, theta: float) -> tuple[Vector, Quaternion]:
    """The turtle's frame in the world frame, as the broadcaster sends it."""
    return (x, y, 0.0), quaternion_from_euler(0.0, 0.0, theta)
