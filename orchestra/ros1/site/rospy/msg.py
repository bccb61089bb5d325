"""rospy.msg: ``AnyMsg`` and rospy's re-export of std_msgs/Header."""
from typing import Any

from orchestra.node.msg import AnyMsg, get_message_class

__all__ = ["AnyMsg", "Header"]  # noqa: F822 - Header is made by __getattr__


def __getattr__(name: str) -> Any:
    # rospy.Header is std_msgs.msg.Header; built only when asked for (messages are lazy)
    if name == "Header":
        return get_message_class("std_msgs/Header")
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
