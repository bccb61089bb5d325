"""Where ROS keeps its files on this machine: ``ROS_HOME``, the log directory, and the
directory of orchestra's own caches under ``ROS_HOME``.

The rules are rospkg's (``get_ros_home``, ``get_log_dir``); the supervisor, the tools and the
``rospkg`` module of the ROS 1 layer all need them, so they live once, at the bottom.
"""
from __future__ import annotations

import os
from collections.abc import Mapping


def ros_home(environ: Mapping[str, str] | None = None) -> str:
    """``$ROS_HOME``, else ``~/.ros`` (rospkg.get_ros_home)."""
    env = os.environ if environ is None else environ
    return env.get("ROS_HOME") or os.path.join(os.path.expanduser("~"), ".ros")


def log_dir_root(environ: Mapping[str, str] | None = None) -> str:
    """``$ROS_LOG_DIR``, else ``$ROS_HOME/log`` (rospkg.get_log_dir)."""
    env = os.environ if environ is None else environ
    return env.get("ROS_LOG_DIR") or os.path.join(ros_home(env), "log")


def cache_dir(environ: Mapping[str, str] | None = None) -> str | None:
    """``$ROS_HOME/orchestra``, else ``~/.ros/orchestra``: orchestra's caches (the package
    index, the standard message definitions); None when no home can be found."""
    env = os.environ if environ is None else environ
    home_dir = env.get("ROS_HOME")
    if home_dir:
        return os.path.join(home_dir, "orchestra")
    home = os.path.expanduser("~")  # falls back to the password database when HOME is unset
    if not home or home == "~":
        return None
    return os.path.join(home, ".ros", "orchestra")
