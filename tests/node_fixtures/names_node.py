#!/usr/bin/env python3
"""Report how this node resolves names and what its private params are, then spin."""
import json

import orchestra.node as rospy

rospy.init_node("namer")
report = {
    "name": rospy.get_name(),
    "namespace": rospy.get_namespace(),
    "chatter": rospy.resolve_name("chatter"),
    "private": rospy.resolve_name("~x"),
    "global": rospy.resolve_name("/abs"),
    "argv": rospy.myargv()[1:],
    "rate": rospy.get_param("~rate", None),
    "label": rospy.get_param("~label", None),
    "missing": rospy.get_param("~nothing", "dflt"),
    "search": rospy.search_param("shared"),
}
print(json.dumps(report), flush=True)
rospy.spin()
print(json.dumps({"shutdown": True}), flush=True)
