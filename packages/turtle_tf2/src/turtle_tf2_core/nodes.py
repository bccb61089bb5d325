"""The two nodes of the tf2 turtle demo, through tf2_ros's API (``orchestra.tf.tf2_ros``).

``broadcast(turtle, pose_topic)``: every turtlesim/Pose on ``pose_topic`` becomes a
geometry_msgs/TransformStamped world -> ``turtle`` sent by a ``TransformBroadcaster``.

``follow(leader, follower, ...)``: spawn ``follower`` at (4, 2) through ``spawn``, then at
10 Hz look up ``leader`` in ``follower``'s frame with ``Buffer.lookup_transform(follower,
leader, Time())`` and publish ``<follower>/cmd_vel``: angular 4 * atan2(y, x), linear
0.5 * hypot(x, y) (the tutorial's gains).
"""
from __future__ import annotations

import math

import orchestra.node as node
from orchestra.node.exceptions import ROSInterruptException, ServiceException
from orchestra.node.msg import get_message_class, get_service_class
from orchestra.tf import quaternion_from_euler, tf2_ros

WORLD_FRAME = "world"
ANGULAR_GAIN = 4.0
LINEAR_GAIN = 0.5
FOLLOW_RATE_HZ = 10.0
SPAWN_AT = (4.0, 2.0, 0.0)


def pose_to_transform(msg, turtle: str, stamp):
    """The turtle's pose as the TransformStamped world -> turtle."""
    t = get_message_class("geometry_msgs/TransformStamped")()
    t.header.stamp = stamp
    t.header.frame_id = WORLD_FRAME
    t.child_frame_id = turtle
    t.transform.translation.x, t.transform.translation.y = msg.x, msg.y
    t.transform.translation.z = 0.0
    r = t.transform.rotation
    r.x, r.y, r.z, r.w = quaternion_from_euler(0.0, 0.0, msg.theta)
    return t


def steer(transform) -> tuple[float, float]:
    """(linear, angular) towards the target whose TransformStamped is in the follower's frame."""
    x, y = transform.transform.translation.x, transform.transform.translation.y
    return LINEAR_GAIN * math.hypot(x, y), ANGULAR_GAIN * math.atan2(y, x)


def broadcast(turtle: str, pose_topic: str) -> None:
    """Publish the turtle's pose as a tf2 frame until shutdown."""
    broadcaster = tf2_ros.TransformBroadcaster()
    pose_class = get_message_class("turtlesim/Pose")

    def on_pose(msg) -> None:
        broadcaster.sendTransform(pose_to_transform(msg, turtle, node.Time.now()))

    node.Subscriber(pose_topic, pose_class, on_pose, queue_size=10)
    node.spin()


def follow(leader: str = "turtle1", follower: str = "turtle2",
           retry_after: float | None = None, warn: bool = False) -> None:
    """Spawn ``follower`` and steer it towards ``leader`` until shutdown. A failed lookup
    (frames not broadcast yet) waits one period, or ``retry_after`` seconds; with ``warn``
    it is logged (the C++ tutorial's behaviour)."""
    tf_buffer = tf2_ros.Buffer()
    listener = tf2_ros.TransformListener(tf_buffer)  # noqa: F841 - feeds tf_buffer
    node.wait_for_service("spawn")
    try:
        node.ServiceProxy("spawn", get_service_class("turtlesim/Spawn"))(
            x=SPAWN_AT[0], y=SPAWN_AT[1], theta=SPAWN_AT[2], name=follower)
    except ServiceException as exc:  # already there (a restarted listener): just drive it
        node.logwarn("could not spawn %s: %s", follower, exc)
    twist_class = get_message_class("geometry_msgs/Twist")
    cmd_vel = node.Publisher(f"{follower}/cmd_vel", twist_class, queue_size=1)
    rate = node.Rate(FOLLOW_RATE_HZ)
    try:
        while not node.is_shutdown():
            try:
                transform = tf_buffer.lookup_transform(follower, leader, node.Time())
            except tf2_ros.TransformException as exc:
                if warn:
                    node.logwarn("%s", exc)
                if retry_after is not None:
                    node.sleep(retry_after)
                else:
                    rate.sleep()
                continue
            twist = twist_class()
            twist.linear.x, twist.angular.z = steer(transform)
            cmd_vel.publish(twist)
            rate.sleep()
    except ROSInterruptException:
        pass
