#!/usr/bin/env python3
"""Publish COUNT std_msgs/String messages ``n <i>`` on TOPIC at RATE Hz once a subscriber is
connected: burst.py TOPIC COUNT RATE [--latch] [--name NAME]. Runs on orchestra's node API
or on real rospy (whichever the interpreter has), prints JSON lines."""
import argparse
import json

try:
    import rospy
    from rospy import AnyMsg  # noqa: F401
    from std_msgs.msg import String
except ImportError:
    import orchestra.node as rospy
    String = rospy.get_message_class("std_msgs/String")

parser = argparse.ArgumentParser()
parser.add_argument("topic")
parser.add_argument("count", type=int)
parser.add_argument("rate", type=float)
parser.add_argument("--latch", action="store_true")
parser.add_argument("--name", default="burst")
opts = parser.parse_args(rospy.myargv()[1:])

rospy.init_node(opts.name)
pub = rospy.Publisher(opts.topic, String, queue_size=opts.count + 10, latch=opts.latch)
print(json.dumps({"ready": rospy.get_name()}), flush=True)
while pub.get_num_connections() < 1 and not rospy.is_shutdown():
    rospy.sleep(0.01)
rate = rospy.Rate(opts.rate)
for i in range(opts.count):
    pub.publish(String(data=f"n {i}"))
    rate.sleep()
print(json.dumps({"sent": opts.count}), flush=True)
rospy.spin()
