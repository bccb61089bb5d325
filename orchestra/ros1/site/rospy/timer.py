"""rospy.timer: sleep, Rate and Timer of orchestra's runtime."""
from orchestra.node.rostime import Rate, sleep
from orchestra.node.timer import Timer, TimerEvent

__all__ = ["Rate", "Timer", "TimerEvent", "sleep"]
