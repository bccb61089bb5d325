#!/usr/bin/env python3
# actionlib_tutorials' Fibonacci client: sends order ~order (default 10) to ~server
# (default "fibonacci"), logs the feedback count and the result.
from __future__ import print_function

import sys

import rospy
import actionlib

import beginner_tutorials.msg

feedbacks = []


def fibonacci_client(server, order):
    # Creates the SimpleActionClient, passing the type of the action
    # (FibonacciAction) to the constructor.
    client = actionlib.SimpleActionClient(server, beginner_tutorials.msg.FibonacciAction)

    # Waits until the action server has started up and started
    # listening for goals.
    client.wait_for_server()

    # Creates a goal to send to the action server.
    goal = beginner_tutorials.msg.FibonacciGoal(order=order)

    # Sends the goal to the action server.
    client.send_goal(goal, feedback_cb=lambda fb: feedbacks.append(list(fb.sequence)))

    # Waits for the server to finish performing the action.
    client.wait_for_result()

    # Prints out the result of executing the action
    return client.get_state(), client.get_result()  # A FibonacciResult


if __name__ == '__main__':
    try:
        # Initializes a rospy node so that the SimpleActionClient can
        # publish and subscribe over ROS.
        rospy.init_node('fibonacci_client_py')
        state, result = fibonacci_client(rospy.get_param('~server', 'fibonacci'),
                                          rospy.get_param('~order', 10))
        rospy.loginfo("fibonacci result: state %d, sequence %s, %d feedbacks",
                      state, ", ".join([str(n) for n in result.sequence]), len(feedbacks))
        rospy.sleep(0.5)  # let /rosout take the line before the node goes
    except rospy.ROSInterruptException:
        print("program interrupted before completion", file=sys.stderr)
