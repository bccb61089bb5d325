#!/usr/bin/env python3
# The beginner tutorials' service client: add_two_ints_client.py X Y prints the sum. As in
# the tutorial it never calls init_node: rospy lets a plain script call services. (It reads
# rospy.myargv() rather than sys.argv so that roslaunch's __name:= words do not count.)
from __future__ import print_function

import sys
import rospy
from beginner_tutorials.srv import *


def add_two_ints_client(x, y):
    rospy.wait_for_service('add_two_ints')
    try:
        add_two_ints = rospy.ServiceProxy('add_two_ints', AddTwoInts)
        resp1 = add_two_ints(x, y)
        return resp1.sum
    except rospy.ServiceException as e:
        print("Service call failed: %s" % e)


def usage():
    return "%s [x y]" % sys.argv[0]


if __name__ == "__main__":
    argv = rospy.myargv()
    if len(argv) == 3:
        x = int(argv[1])
        y = int(argv[2])
    else:
        print(usage())
        sys.exit(1)
    req = AddTwoIntsRequest(a=x, b=y)
    print("Requesting %s+%s" % (req.a, req.b))
    print("%s + %s = %s" % (x, y, add_two_ints_client(x, y)))
