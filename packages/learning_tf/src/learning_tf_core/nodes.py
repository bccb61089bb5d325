"""The bodies of the tutorial's nodes; the scripts only say where the turtle name comes from.

``broadcast_pose(turtle)``: /<turtle>/pose -> transform world -> <turtle> on /tf.
``follow(leader, follower, ...)``: spawn the follower through the simulator's ``spawn``
service, then steer it towards the leader at 10 Hz from tf lookups.
"""
from __future__ import annotations

import orchestra.node as node
from learning_tf_core.follow import WORLD_FRAME, follow_command, pose_to_transform
from orchestra.node.exceptions import ROSInterruptException, ServiceException
from orchestra.node.msg import get_message_class, get_service_class
from orchestra.tf import TransformBroadcaster, TransformException, TransformListener

FOLLOW_RATE_HZ = 10.0


def broadcast_pose(turtle: str) -> None:
    """Publish the turtle's pose as a tf frame until shutdown."""
    turtle = turtle.strip("/")
    pose_class = get_message_class("turtlesim/Pose")
    broadcaster = TransformBroadcaster()

    def on_pose(msg) -> None:
        translation, rotation = pose_to_transform(msg.x, msg.y, msg.theta)
        broadcaster.sendTransform(translation, rotation, node.Time.now(), turtle, WORLD_FRAME)

    node.Subscriber(f"/{turtle}/pose", pose_class, on_pose, queue_size=1)
    node.spin()


def follow(leader: str = "turtle1", follower: str = "turtle2",
           spawn_at: tuple[float, float, float] = (4.0, 2.0, 0.0)) -> None:
    """Spawn ``follower`` and chase ``leader`` until shutdown."""
    spawn = get_service_class("turtlesim/Spawn")
    twist_class = get_message_class("geometry_msgs/Twist")
    listener = TransformListener()
    node.wait_for_service("spawn")
    try:
        node.ServiceProxy("spawn", spawn)(x=spawn_at[0], y=spawn_at[1], theta=spawn_at[2],
                                          name=follower)
    except ServiceException as exc:  # already there (a restarted listener): just drive it
        node.logwarn("could not spawn %s: %s", follower, exc)
    cmd = node.Publisher(f"{follower}/cmd_vel", twist_class, queue_size=1)
    rate = node.Rate(FOLLOW_RATE_HZ)
    while not node.is_shutdown():
        try:
            (x, y, _), _ = listener.lookupTransform(f"/{follower}", f"/{leader}", node.Time(0))
        except TransformException:
            x = y = None
        if x is not None:
            linear, angular = follow_command(x, y)
            twist = twist_class()
            twist.linear.x, twist.angular.z = linear, angular
            cmd.publish(twist)
        try:
            rate.sleep()
        except ROSInterruptException:
            break
