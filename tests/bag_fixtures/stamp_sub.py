#!/usr/bin/env python3
"""Print each message on TOPIC (any type) as a JSON line with its wall receipt time:
stamp_sub.py TOPIC [--name NAME]. std_msgs/String payloads are decoded from the raw bytes.
Runs on real rospy or on orchestra's node API, so both sides are the same program."""
import argparse
import json
import struct
import time

try:
    import rospy
except ImportError:
    import orchestra.node as rospy

parser = argparse.ArgumentParser()
parser.add_argument("topic")
parser.add_argument("--name", default="stamp_sub")
opts = parser.parse_args(rospy.myargv()[1:])


def callback(msg):
    now = time.time()
    raw = bytes(msg._buff)
    header = msg._connection_header
    text = None
    if header.get("type") == "std_msgs/String":
        (size,) = struct.unpack_from("<I", raw)
        text = raw[4:4 + size].decode()
    print(json.dumps({"t": now, "data": text, "type": header.get("type"),
                      "latching": header.get("latching")}), flush=True)


rospy.init_node(opts.name, anonymous=True)
sub = rospy.Subscriber(opts.topic, rospy.AnyMsg, callback, queue_size=None)
print(json.dumps({"ready": rospy.get_name()}), flush=True)
while not rospy.is_shutdown():
    if sub.get_num_connections() > 0:
        print(json.dumps({"connected": True}), flush=True)
        break
    time.sleep(0.02)
rospy.spin()
