#!/usr/bin/env python3
"""A node driven by commands on stdin, for the simulated-time tests; reports JSON lines.

    simtime.py [--ros1] clock      publish each number read from stdin on /clock (latched,
                                   on wall time itself: disable_rostime, as a simulator does)
    simtime.py [--ros1] follow     a node under test; commands, one per line:
        now                        -> {"now": ns, "time": get_time()}
        until NS                   -> wait (wall, at most 10 s) for Time.now() >= NS, then "now"
        sleep SECS                 -> {"sleeping": ns}, then {"slept": ns} or {"error": ...}
        rate HZ N                  -> {"rate": ns} then N x {"tick": i, "now": ns} (or an error)
        timer SECS                 -> {"timer": ns}; each tick {"fired": real ns, "expected": ns}

"sleeping" and "timer" are reported once the sleeping thread waits on the clock, i.e. once
it has taken its start time: a /clock message the test sends after them cannot be mistaken
for the start.

With ``--ros1`` (run by /usr/bin/python3) it is the same program on Debian's real rospy.
"""
import json
import sys
import threading
import time

if "--ros1" in sys.argv:
    import rospy
    from rosgraph_msgs.msg import Clock
else:
    import orchestra.node as rospy
    from orchestra.node.msg import get_message_class

    Clock = get_message_class("rosgraph_msgs/Clock")

lock = threading.Lock()


def emit(**fields):
    with lock:
        print(json.dumps(fields), flush=True)


def now_ns():
    return rospy.Time.now().to_nsec()


def error(exc):
    fields = {"error": type(exc).__name__,
              "interrupt": isinstance(exc, rospy.ROSInterruptException)}
    if isinstance(exc, rospy.ROSTimeMovedBackwardsException):
        fields["jump"] = exc.time
    emit(**fields)


def clock():
    rospy.init_node("clock", disable_rostime=True)
    pub = rospy.Publisher("/clock", Clock, queue_size=10, latch=True)
    emit(ready=rospy.get_name(), wallclock_now=now_ns())
    for line in sys.stdin:
        if line.strip():
            stamp = rospy.Time.from_sec(float(line))
            pub.publish(Clock(clock=stamp))
            emit(published=stamp.to_nsec())


def follow():
    rospy.init_node("follower")
    emit(ready=rospy.get_name(), now=now_ns(), time=rospy.get_time())
    for line in sys.stdin:
        words = line.split()
        if not words:
            continue
        try:
            run(words[0], words[1:])
        except rospy.ROSInterruptException as exc:
            error(exc)
        if rospy.is_shutdown():
            break


def waiting(thread, timeout=10.0):
    """Return once ``thread`` blocks in a Condition/Event wait (or ends). Both rospy and
    orchestra wait for /clock there."""
    deadline = time.monotonic() + timeout
    while thread.is_alive() and time.monotonic() < deadline:
        frame = sys._current_frames().get(thread.ident)
        if frame is not None and frame.f_code.co_name == "wait" \
                and frame.f_code.co_filename == threading.__file__:
            return
        time.sleep(0.002)


def sleeper(secs):
    try:
        rospy.sleep(secs)
        emit(slept=now_ns())
    except rospy.ROSInterruptException as exc:
        error(exc)


def run(command, args):
    if command == "now":
        emit(now=now_ns(), time=rospy.get_time())
    elif command == "until":
        deadline = time.monotonic() + 10
        while now_ns() < int(args[0]) and time.monotonic() < deadline:
            time.sleep(0.005)
        emit(now=now_ns(), time=rospy.get_time())
    elif command == "sleep":  # in a thread, so that the main thread can tell when it waits
        thread = threading.Thread(target=sleeper, args=(float(args[0]),), daemon=True)
        thread.start()
        waiting(thread)
        emit(sleeping=now_ns())
        while thread.is_alive():
            thread.join(0.05)
    elif command == "rate":
        rate = rospy.Rate(float(args[0]))
        emit(rate=now_ns())
        for i in range(int(args[1])):
            rate.sleep()
            emit(tick=i, now=now_ns())
    elif command == "timer":
        def fired(event):
            emit(fired=event.current_real.to_nsec(), expected=event.current_expected.to_nsec())
        waiting(rospy.Timer(rospy.Duration.from_sec(float(args[0])), fired))
        emit(timer=now_ns())
    else:
        emit(unknown=command)


if __name__ == "__main__":
    {"clock": clock, "follow": follow}[[a for a in sys.argv[1:] if a != "--ros1"][0]]()
