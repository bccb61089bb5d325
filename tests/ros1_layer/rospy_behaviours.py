#!/usr/bin/env python3
"""rospy behaviours beyond the tutorials, as one node that prints a JSON line per check.

Run by tests/test_ros1_layer.py under orchestra's layer (and, where installed, under
Debian's real rospy: the same expectations hold for both). Uses only rospy's and roslib's
API, so it runs unchanged on either."""
import json
import sys
import threading

import rospy
from roslib.message import get_message_class, get_service_class

String = get_message_class("std_msgs/String")
SetBool = get_service_class("std_srvs/SetBool")
Trigger = get_service_class("std_srvs/Trigger")


def emit(**kv):
    sys.stdout.write(json.dumps(kv) + "\n")
    sys.stdout.flush()


class Greeter(rospy.SubscribeListener):
    """Greets each new subscriber of /greeted with a message for it alone."""

    def __init__(self):
        self.peers = 0

    def peer_subscribe(self, topic_name, topic_publish, peer_publish):
        self.peers += 1
        peer_publish(String(data=f"welcome {self.peers}"))


# rospy lets a script create topics before init_node; they register once the node runs
early = rospy.Publisher("early", String, queue_size=1, latch=True)
try:
    early.publish(String(data="too soon"))
    emit(publish_before_init="accepted")
except rospy.ROSException:
    emit(publish_before_init="refused")

rospy.init_node("behaviours", log_level=rospy.DEBUG)
early.publish(String(data="after init"))
got = rospy.wait_for_message("early", String, timeout=10)
emit(early_topic=got.data)

greeter = Greeter()
greeted = rospy.Publisher("greeted", String, subscriber_listener=greeter, queue_size=10)
first = rospy.wait_for_message("greeted", String, timeout=10)
emit(greeting=first.data)

errors = []


def failing(req):
    raise ValueError(f"no {req.data}")


rospy.Service("~fail", SetBool, failing,
              error_handler=lambda exc, exc_type, value, tb: errors.append(str(exc)))
rospy.wait_for_service("~fail", timeout=10)
try:
    rospy.ServiceProxy("~fail", SetBool)(True)
    emit(service_error=None)
except rospy.ServiceException as exc:
    emit(service_error="no True" in str(exc), error_handler=errors)

# a handler that returns None gives no answer: the caller gets an error (error_handler is
# only for exceptions the handler raised)
none_errors = []
rospy.Service("~none", Trigger, lambda req: None,
              error_handler=lambda exc, exc_type, value, tb: none_errors.append(str(exc)))
rospy.wait_for_service("~none", timeout=10)
try:
    rospy.ServiceProxy("~none", Trigger)()
    emit(none_handler=None)
except rospy.ServiceException as exc:
    emit(none_handler="service handler returned None" in str(exc), error_handler=none_errors)

for i in range(3):
    rospy.logdebug_once("debug once %d", i)
    rospy.loginfo_throttle(60, "throttled %d", i)
emit(master_pid_code=rospy.get_master().getPid()[0])
emit(names=[rospy.get_name(), rospy.get_namespace(), rospy.resolve_name("x"),
            rospy.resolve_name("~y"), rospy.names.get_caller_id()])
emit(myargv=rospy.myargv(["script", "a:=b", "arg"]))
emit(time=[isinstance(rospy.get_time(), float), rospy.Time.now() > rospy.Time(0),
           rospy.Duration(1.5).to_sec(), rospy.Time(3, 5).to_nsec()])
stopped = threading.Event()
rospy.on_shutdown(stopped.set)
rospy.signal_shutdown("done")
stopped.wait(5)
emit(shutdown=[rospy.is_shutdown(), stopped.is_set()])
