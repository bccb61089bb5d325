"""rospy.rostime: orchestra's Time and Duration (wall or /clock time, as rospy's)."""
from orchestra.node.rostime import Duration, Time, get_rostime, get_time, is_wallclock

__all__ = ["Duration", "Time", "get_rostime", "get_time", "is_wallclock"]
