"""actionlib for orchestra's ROS 1 layer: SimpleActionServer and SimpleActionClient over
actionlib's five topics (see ``goals``), interoperable with real actionlib nodes.
``actionlib.GoalStatus`` (and ``GoalID``, ``GoalStatusArray``) are actionlib_msgs' classes,
as in actionlib."""
from typing import Any

from . import goals
from .simple_action_client import SimpleActionClient, SimpleGoalState
from .simple_action_server import SimpleActionServer

__all__ = ["GoalID", "GoalStatus", "GoalStatusArray", "SimpleActionClient",  # noqa: F822
           "SimpleActionServer", "SimpleGoalState"]

_MESSAGES = {"GoalID": goals.goal_id_class, "GoalStatus": goals.status_class,
             "GoalStatusArray": goals.status_array_class}


def __getattr__(name: str) -> Any:
    if name in _MESSAGES:
        return _MESSAGES[name]()
    raise AttributeError(f"module 'actionlib' has no attribute {name!r}")
