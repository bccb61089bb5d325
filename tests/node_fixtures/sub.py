#!/usr/bin/env python3
"""Print every message received on TOPIC as a JSON line: sub.py TOPIC TYPE [--name NAME]."""
import argparse
import json
import time

import orchestra.node as rospy
from orchestra.node.msg import AnyMsg, get_message_class, to_plain

parser = argparse.ArgumentParser()
parser.add_argument("topic")
parser.add_argument("type")
parser.add_argument("--name", default="sub")
parser.add_argument("--queue", type=int, default=10)
parser.add_argument("--slow", type=float, default=0.0, help="seconds spent in each callback")
opts = parser.parse_args(rospy.myargv()[1:])

cls = AnyMsg if opts.type == "*" else get_message_class(opts.type)


def callback(msg):
    if cls is AnyMsg:
        body = {"type": msg._connection_header["type"], "size": len(msg._buff)}
    else:
        body = to_plain(msg)
    print(json.dumps({"msg": body, "latching": msg._connection_header.get("latching")}),
          flush=True)
    if opts.slow:
        time.sleep(opts.slow)


rospy.init_node(opts.name)
sub = rospy.Subscriber(opts.topic, cls, callback, queue_size=opts.queue)
print(json.dumps({"ready": rospy.get_name(), "topic": sub.resolved_name}), flush=True)
rospy.spin()
print(json.dumps({"shutdown": True}), flush=True)
