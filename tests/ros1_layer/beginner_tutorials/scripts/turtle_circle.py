#!/usr/bin/env python3
# Drives turtlesim's turtle1 in a circle (cmd_vel) and logs where it is (pose).
import rospy
from geometry_msgs.msg import Twist
from turtlesim.msg import Pose

poses = []


def on_pose(pose):
    poses.append(pose)
    rospy.loginfo_throttle(0.5, "turtle1 at x=%.2f y=%.2f theta=%.2f" % (pose.x, pose.y,
                                                                       pose.theta))


if __name__ == '__main__':
    rospy.init_node('turtle_circle')
    speed = rospy.get_param('~speed', 2.0)
    pub = rospy.Publisher('turtle1/cmd_vel', Twist, queue_size=1)
    rospy.Subscriber('turtle1/pose', Pose, on_pose)
    rate = rospy.Rate(10)
    while not rospy.is_shutdown():
        twist = Twist()
        twist.linear.x = speed
        twist.angular.z = 1.0
        pub.publish(twist)
        try:
            rate.sleep()
        except rospy.ROSInterruptException:
            break
