#!/usr/bin/env python3
"""actionlib's SimpleActionServer/SimpleActionClient semantics as one node printing JSON
lines: feedback, success, a newer goal preempting the running one, a cancel, and the
goal/preempt-callback style of server. Uses only rospy/actionlib API and actionlib's own
TwoInts action, so it runs unchanged under real actionlib and under orchestra's layer
(tests/test_ros1_layer.py compares the two)."""
import json
import sys
import threading

import actionlib
import rospy
from actionlib.msg import TwoIntsAction, TwoIntsFeedback, TwoIntsGoal, TwoIntsResult


def emit(**kv):
    sys.stdout.write(json.dumps(kv, sort_keys=True) + "\n")
    sys.stdout.flush()


def execute(goal):
    """Adds a + b slowly; b < 0 means 'run until preempted'."""
    rate = rospy.Rate(50)
    for _ in range(1000 if goal.b < 0 else 5):
        if server.is_preempt_requested():
            server.set_preempted(TwoIntsResult(sum=-1), "preempted")
            return
        server.publish_feedback(TwoIntsFeedback())
        rate.sleep()
    server.set_succeeded(TwoIntsResult(sum=goal.a + goal.b), "added")


rospy.init_node("actions")
server = actionlib.SimpleActionServer("adder", TwoIntsAction, execute_cb=execute,
                                      auto_start=False)
server.start()

first = actionlib.SimpleActionClient("adder", TwoIntsAction)
second = actionlib.SimpleActionClient("adder", TwoIntsAction)
emit(server_found=[first.wait_for_server(rospy.Duration(10)),
                   second.wait_for_server(rospy.Duration(10))])

feedback = []
done = []
first.send_goal(TwoIntsGoal(a=2, b=3), done_cb=lambda s, r: done.append([s, r.sum]),
                feedback_cb=lambda f: feedback.append(1))
emit(succeeded=[first.wait_for_result(rospy.Duration(10)), first.get_state(),
                first.get_result().sum, first.get_goal_status_text(), done,
                len(feedback) > 0, actionlib.SimpleGoalState.DONE])

active = threading.Event()
first.send_goal(TwoIntsGoal(a=1, b=-1), active_cb=active.set)
active.wait(10)
second.send_goal(TwoIntsGoal(a=4, b=5))
emit(preempted_by_newer=[first.wait_for_result(rospy.Duration(10)), first.get_state(),
                         first.get_result().sum],
     newer_ran=[second.wait_for_result(rospy.Duration(10)), second.get_state(),
                second.get_result().sum])

active.clear()
first.send_goal(TwoIntsGoal(a=1, b=-1), active_cb=active.set)
active.wait(10)
first.cancel_goal()
emit(cancelled=[first.wait_for_result(rospy.Duration(10)), first.get_state(),
                first.get_goal_status_text()])
emit(states=[actionlib.GoalStatus.PENDING, actionlib.GoalStatus.SUCCEEDED,
             actionlib.GoalStatus.PREEMPTED])
