"""orchestra: roslaunch-compatible launch and configuration orchestration, without ROS."""

__version__ = "0.1.0"
