#!/usr/bin/env python3
"""Publishes std_msgs/String on ``chatter`` at ``~rate`` Hz (for hztest)."""
import orchestra.node as node
from orchestra.node.msg import get_message_class

String = get_message_class("std_msgs/String")
node.init_node("talker")
pub = node.Publisher("chatter", String, queue_size=10)
rate = node.Rate(float(node.get_param("~rate", 10.0)))
while not node.is_shutdown():
    pub.publish(String(data="hello"))
    try:
        rate.sleep()
    except node.ROSInterruptException:
        break
