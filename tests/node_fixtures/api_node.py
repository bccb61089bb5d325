#!/usr/bin/env python3
"""Exercise the parameter, waiting, logging and shutdown API; print one JSON report.

Expects a publisher of std_msgs/String on /feed (started by the test)."""
import json
import time

import orchestra.node as rospy
from orchestra.node.msg import get_message_class
from orchestra.node.runtime import get_runtime

String = get_message_class("std_msgs/String")
report = {}
rospy.init_node("api")

rospy.set_param("~gain", 2.5)
rospy.set_param("config", {"a": 1, "b": {"c": "x"}})
report["has"] = rospy.has_param("~gain")
report["gain"] = rospy.get_param("/api/gain")
report["config"] = rospy.get_param("config")
report["leaf"] = rospy.get_param("config/b/c")
rospy.delete_param("~gain")
try:
    rospy.get_param("~gain")
    report["deleted"] = False
except KeyError:
    report["deleted"] = True
report["default"] = rospy.get_param("~gain", 7)
try:
    rospy.delete_param("~never_set")
    report["delete_missing"] = "no error"
except KeyError:
    report["delete_missing"] = "KeyError"

try:
    rospy.wait_for_message("/silence", String, timeout=0.3)
    report["wait_timeout"] = False
except rospy.ROSException:
    report["wait_timeout"] = True
report["feed"] = rospy.wait_for_message("/feed", String, timeout=10).data

pub = rospy.Publisher("/api_out", String, queue_size=1)
pub.publish(data="by keyword")
pub.publish("positional")
report["published"] = True

rosout = get_runtime().rosout  # wait until the test's /rosout reader is connected
deadline = time.monotonic() + 10
while rosout.get_num_connections() < 1 and time.monotonic() < deadline:
    time.sleep(0.01)
rospy.loginfo("hello %s", "log")
rospy.logerr("an error")
hooks = []
rospy.on_shutdown(lambda: hooks.append("plain"))
rospy.on_shutdown(lambda reason: hooks.append(reason))
rospy.signal_shutdown("test over")
report["is_shutdown"] = rospy.is_shutdown()
try:
    rospy.Rate(10).sleep()
    rospy.Rate(10).sleep()
    report["sleep_raised"] = False
except rospy.ROSInterruptException:
    report["sleep_raised"] = True
rospy.spin()  # returns at once: shutdown already requested; waits for the cleanup
report["hooks"] = hooks
print(json.dumps(report), flush=True)
