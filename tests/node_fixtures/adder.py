#!/usr/bin/env python3
"""Serve NAME (test_msgs/AddTwoInts): a + b, an error for negative a; NAME defaults to add."""
import json

import orchestra.node as rospy
from orchestra.node.msg import get_service_class

AddTwoInts = get_service_class("test_msgs/AddTwoInts")
args = rospy.myargv()[1:]


def handle(req):
    if req.a < 0:
        raise ValueError(f"negative a: {req.a}")
    return AddTwoInts.Response(sum=req.a + req.b)


rospy.init_node("adder")
srv = rospy.Service(args[0] if args else "add", AddTwoInts, handle)
print(json.dumps({"ready": rospy.get_name(), "service": srv.resolved_name}), flush=True)
rospy.spin()
