#!/usr/bin/env python3
"""One node program for both sides of the interop tests.

Run with ``/usr/bin/python3`` it is a real rospy node (Debian's ROS 1); run with
``--orchestra`` under orchestra's interpreter it is the same program on
``orchestra.node``. Because the two share every line but the imports, a test that passes
one way and fails the other points at orchestra, not at a difference in the test nodes.

    peer.py [--orchestra] [--name N] MODE ...
    MODE pub TOPIC TYPE YAML [--latch] [--rate HZ] [--count N]
         sub TOPIC TYPE
         serve SERVICE TYPE          (std_srvs/Empty, std_srvs/SetBool or std_srvs/Trigger;
                                      SetBool data=false makes the handler raise, Trigger's
                                      handler returns None)
         call SERVICE TYPE YAML... [--persistent]   one call per YAML word
         params                       report ~private / relative / searched params
         watch KEY                    print get_param_cached(KEY) each time it changes
         log TEXT                     loginfo/logwarn TEXT every 0.1 s (TEXT n / TEXT warn n)

Everything it sees is printed as one JSON line (``{"ready": ...}`` first).
Remaps and ``_param:=value`` words after the arguments are honoured (rospy's rules).
"""
import argparse
import json
import sys
import time

parser = argparse.ArgumentParser()
parser.add_argument("--orchestra", action="store_true")
parser.add_argument("--name", default="peer")
parser.add_argument("mode")
parser.add_argument("args", nargs="*")
parser.add_argument("--latch", action="store_true")
parser.add_argument("--rate", type=float, default=20.0)
parser.add_argument("--count", type=int, default=0)
parser.add_argument("--persistent", action="store_true")
parser.add_argument("--anonymous", action="store_true")

if "--orchestra" in sys.argv:
    import orchestra.node as rospy
    from orchestra.node.msg import fill_message, get_message_class, get_service_class

    def make(cls, value):
        return fill_message(cls(), value)
else:
    import genpy.message
    import rospy
    from roslib.message import get_message_class, get_service_class

    def make(cls, value):
        msg = cls()
        genpy.message.fill_message_args(msg, [value])
        return msg

import yaml  # noqa: E402


def emit(**fields):
    print(json.dumps(fields), flush=True)


def plain(value):
    """A message as JSON-able data (same for genpy and orchestra classes)."""
    if type(value).__name__ in ("Time", "Duration"):
        return {"secs": value.secs, "nsecs": value.nsecs}
    if hasattr(value, "__slots__") and hasattr(value, "_slot_types"):
        return {slot: plain(getattr(value, slot)) for slot in value.__slots__
                if not slot.startswith("_")}
    if isinstance(value, (list, tuple)):
        return [plain(v) for v in value]
    if isinstance(value, (bytes, bytearray)):
        return list(value)
    return value


opts = parser.parse_args(rospy.myargv(sys.argv)[1:])
impl = "orchestra" if opts.orchestra else "rospy"


def run_pub(topic, type_name, text):
    cls = get_message_class(type_name)
    rospy.init_node(opts.name, anonymous=opts.anonymous)
    pub = rospy.Publisher(topic, cls, queue_size=10, latch=opts.latch)
    emit(ready=rospy.get_name(), topic=pub.resolved_name, md5=cls._md5sum)
    sent = 0
    rate = rospy.Rate(opts.rate)
    while not rospy.is_shutdown() and (opts.count == 0 or sent < opts.count):
        pub.publish(make(cls, yaml.safe_load(text.replace("$N", str(sent)))))
        sent += 1
        try:
            rate.sleep()
        except rospy.ROSInterruptException:
            break
    emit(sent=sent)
    rospy.spin()


def run_sub(topic, type_name):
    cls = get_message_class(type_name)

    def callback(msg):
        header = getattr(msg, "_connection_header", None) or {}
        emit(msg=plain(msg), callerid=header.get("callerid"), latching=header.get("latching"),
             type=header.get("type"), md5sum=header.get("md5sum"),
             definition=header.get("message_definition"))

    rospy.init_node(opts.name, anonymous=opts.anonymous)
    sub = rospy.Subscriber(topic, cls, callback)
    emit(ready=rospy.get_name(), topic=sub.resolved_name)
    rospy.spin()


def run_serve(service, type_name):
    cls = get_service_class(type_name)
    calls = []

    def handle(req):
        calls.append(1)
        if type_name.endswith("SetBool"):
            if not req.data:
                raise ValueError(f"refused by {impl}")
            return cls._response_class(success=True, message=f"{impl} call {len(calls)}")
        if type_name.endswith("Trigger"):
            return None  # no answer: rospy reports an error to the caller
        return cls._response_class()

    rospy.init_node(opts.name, anonymous=opts.anonymous)
    srv = rospy.Service(service, cls, handle)
    emit(ready=rospy.get_name(), service=srv.resolved_name)
    rospy.spin()


def run_call(service, type_name, *texts):
    cls = get_service_class(type_name)
    rospy.init_node(opts.name, anonymous=opts.anonymous)
    emit(ready=rospy.get_name())
    rospy.wait_for_service(service, timeout=10)
    proxy = rospy.ServiceProxy(service, cls, persistent=opts.persistent)
    results = []
    for text in texts:
        request = make(cls._request_class, yaml.safe_load(text) or {})
        try:
            results.append({"ok": plain(proxy(request))})
        except rospy.ServiceException as exc:
            results.append({"error": str(exc)})
    if opts.persistent:
        proxy.close()
    emit(results=results)


def run_params():
    rospy.init_node(opts.name, anonymous=opts.anonymous)
    report = {"name": rospy.get_name(), "namespace": rospy.get_namespace()}
    for key in ("~speed", "~gains", "relative", "/absolute", "~missing"):
        report[key] = rospy.get_param(key, "<default>")
    report["search"] = rospy.search_param("shared")
    rospy.set_param("~written", {"by": impl, "n": [1, 2]})
    report["written"] = rospy.get_param("~written")
    report["has_written"] = rospy.has_param("~written")
    rospy.delete_param("~written")
    report["has_after_delete"] = rospy.has_param("~written")
    report["names"] = sorted(n for n in rospy.get_param_names() if n.startswith("/interop"))
    emit(ready=rospy.get_name(), params=report)
    rospy.spin()


def run_watch(key):
    rospy.init_node(opts.name, anonymous=opts.anonymous)
    last = object()
    emit(ready=rospy.get_name(), value=rospy.get_param_cached(key, None))
    while not rospy.is_shutdown():
        value = rospy.get_param_cached(key, None)
        if value != last:
            emit(value=value)
            last = value
        time.sleep(0.02)


def run_log(text):
    rospy.init_node(opts.name, anonymous=opts.anonymous)
    emit(ready=rospy.get_name())
    sent = 0
    while not rospy.is_shutdown():
        rospy.loginfo("%s %d", text, sent)
        rospy.logwarn("%s warn %d", text, sent)
        sent += 1
        time.sleep(0.1)


MODES = {"pub": run_pub, "sub": run_sub, "serve": run_serve, "call": run_call,
         "params": run_params, "watch": run_watch, "log": run_log}
MODES[opts.mode](*opts.args)
