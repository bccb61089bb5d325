#!/usr/bin/env python3
"""Call SERVICE (test_msgs/AddTwoInts) every way ServiceProxy allows, print one JSON report."""
import json

import orchestra.node as rospy
from orchestra.node.msg import get_service_class

AddTwoInts = get_service_class("test_msgs/AddTwoInts")
name = rospy.myargv()[1]
rospy.init_node("caller")
rospy.wait_for_service(name, timeout=10)
plain = rospy.ServiceProxy(name, AddTwoInts)
report = {"plain": plain(2, 3).sum}
persistent = rospy.ServiceProxy(name, AddTwoInts, persistent=True)
report["persistent"] = [persistent(AddTwoInts.Request(a=i, b=1)).sum for i in range(3)]
try:
    plain(a=-5, b=0)
    report["error"] = False
except rospy.ServiceException:
    report["error"] = True
try:
    rospy.ServiceProxy("/no/such/service", AddTwoInts)(a=1, b=1)
    report["missing"] = False
except rospy.ServiceException:
    report["missing"] = True
try:
    rospy.wait_for_service("/no/such/service", timeout=0.2)
    report["timeout"] = False
except rospy.ROSException:
    report["timeout"] = True
persistent.close()
print(json.dumps(report), flush=True)
