#!/usr/bin/env python3
"""Publish TYPE messages built from YAML on TOPIC: pub.py TOPIC TYPE YAML [--latch]
[--rate HZ] [--count N] [--name NAME] (remaps and _params after them are honoured)."""
import argparse
import json
import sys

import yaml

import orchestra.node as rospy
from orchestra.node.msg import fill_message, get_message_class

parser = argparse.ArgumentParser()
parser.add_argument("topic")
parser.add_argument("type")
parser.add_argument("yaml")
parser.add_argument("--latch", action="store_true")
parser.add_argument("--rate", type=float, default=20.0)
parser.add_argument("--count", type=int, default=0, help="0 = forever")
parser.add_argument("--name", default="pub")
parser.add_argument("--report", action="store_true", help="print connection count changes")
opts = parser.parse_args(rospy.myargv()[1:])

cls = get_message_class(opts.type)
rospy.init_node(opts.name)
pub = rospy.Publisher(opts.topic, cls, queue_size=10, latch=opts.latch)
print(json.dumps({"ready": rospy.get_name(), "topic": pub.resolved_name}), flush=True)
sent = 0
connections = 0
rate = rospy.Rate(opts.rate)
while not rospy.is_shutdown() and (opts.count == 0 or sent < opts.count):
    if opts.report and pub.get_num_connections() != connections:
        connections = pub.get_num_connections()
        print(json.dumps({"connections": connections}), flush=True)
    msg = fill_message(cls(), yaml.safe_load(opts.yaml.replace("$N", str(sent))))
    pub.publish(msg)
    sent += 1
    try:
        rate.sleep()
    except rospy.ROSInterruptException:
        break
if opts.count:
    print(json.dumps({"sent": sent}), flush=True)
    rospy.spin()
sys.exit(0)
