#!/usr/bin/env python3
"""A node that logs on request, for the logger-level tests (tests/test_node_loggers.py).

    logger_node.py [--name N] [--rosout-subscribers K] [--disable-rosout]

Prints ``{"ready": name}`` once K nodes are connected to its /rosout publisher. Each line R
read from stdin is one round: ``logdebug("round R debug")``, ``loginfo(... info)``,
``logwarn(... warn)``, then ``logfatal("round R end")`` (above any level, so it marks the end
of the round on the console and on /rosout), then ``{"round": R}`` on stdout. DEBUG and
INFO console lines go to stdout before that report; WARN and FATAL to stderr.
"""
import argparse
import json
import queue
import sys
import threading
import time

import orchestra.node as rospy
from orchestra.node.runtime import get_runtime

parser = argparse.ArgumentParser()
parser.add_argument("--name", default="talk")
parser.add_argument("--rosout-subscribers", type=int, default=0)
parser.add_argument("--disable-rosout", action="store_true")
opts = parser.parse_args(rospy.myargv()[1:])

rospy.init_node(opts.name, disable_rosout=opts.disable_rosout)
rosout = getattr(get_runtime(), "rosout", None)
deadline = time.monotonic() + 20
while (opts.rosout_subscribers and rosout.get_num_connections() < opts.rosout_subscribers
       and time.monotonic() < deadline):
    time.sleep(0.01)
print(json.dumps({"ready": rospy.get_name()}), flush=True)

commands: queue.Queue = queue.Queue()


def read_stdin():  # on a thread: a signal must end the node even while no line comes
    for line in sys.stdin:
        commands.put(line.strip())
    commands.put(None)


threading.Thread(target=read_stdin, daemon=True).start()
while not rospy.is_shutdown():
    try:
        r = commands.get(timeout=0.1)
    except queue.Empty:
        continue
    if r is None:
        break
    rospy.logdebug("round %s debug", r)
    rospy.loginfo("round %s info", r)
    rospy.logwarn("round %s warn", r)
    rospy.logfatal("round %s end", r)
    print(json.dumps({"round": r}), flush=True)
