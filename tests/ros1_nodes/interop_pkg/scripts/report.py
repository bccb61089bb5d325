#!/usr/bin/python3
"""A real rospy node that reports what its launcher gave it: report.py OUT_FILE.

Writes one JSON object to OUT_FILE (name, namespace, ROS_NAMESPACE, how 'chatter' resolves,
its private params, the topics the master lists for it, its argv without remaps), then logs
a line five times a second until shut down. Run by both roslaunch and orchestra launch,
the two reports must agree.
"""
import json
import os
import sys
import xmlrpc.client

import rosgraph
import rospy
from std_msgs.msg import String

rospy.init_node("report")
pub = rospy.Publisher("chatter", String, queue_size=1, latch=True)
pub.publish(String(data="hello"))
name = rospy.get_name()
state = xmlrpc.client.ServerProxy(rosgraph.get_master_uri()).getSystemState(name)[2]
report = {
    "name": name,
    "namespace": rospy.get_namespace(),
    "ROS_NAMESPACE": os.environ.get("ROS_NAMESPACE"),
    "chatter": rospy.resolve_name("chatter"),
    "published": sorted(t for t, nodes in state[0] if name in nodes),
    "private": rospy.get_param("~"),
    "global": rospy.get_param("/interop/global", None),
    "argv": rospy.myargv(sys.argv)[2:],
}
out = rospy.myargv(sys.argv)[1]
with open(out + ".tmp", "w") as stream:
    json.dump(report, stream)
os.rename(out + ".tmp", out)
# log until shut down: whoever runs /rosout (roscore's or orchestra's) must collect it;
# repeated because rospy drops log messages sent before /rosout has connected
rate = rospy.Rate(5)
while not rospy.is_shutdown():
    rospy.loginfo("report written to %s", out)
    try:
        rate.sleep()
    except rospy.ROSInterruptException:
        break
