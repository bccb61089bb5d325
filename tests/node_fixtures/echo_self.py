#!/usr/bin/env python3
"""Publish on /loop and subscribe to /loop in the same node; report what comes back."""
import json

import orchestra.node as rospy
from orchestra.node.msg import get_message_class

String = get_message_class("std_msgs/String")
rospy.init_node("self_loop")
got = []
rospy.Subscriber("/loop", String, lambda m: got.append((m.data, m._connection_header["callerid"])))
pub = rospy.Publisher("/loop", String, queue_size=10)
rate = rospy.Rate(50)
while not got and not rospy.is_shutdown():
    pub.publish(data="mine")
    rate.sleep()
print(json.dumps({"got": got[0]}), flush=True)
