"""What a command-line tool's node needs: the master it talks to, a one-line error when that
master is not up, and this process as an anonymous node for the tool's lifetime.

``orchestra topic|service|node``, ``bag`` and ``plot`` are tools in the sense of rostopic and
rosbag: they speak to the master named by ``ROS_MASTER_URI`` and, to publish or subscribe,
become a short-lived anonymous node. The rules live here once so every tool says the same
thing when the master is down and starts its node the same way.
"""
from __future__ import annotations

import signal
import threading
import time
from types import ModuleType

from orchestra.rpc import MasterUnreachable, master_is_up, master_uri_from_env

# the base name of a tool's anonymous node (rostopic's is rostopic_<pid>_<stamp>)
CLI_NODE = "orchestra_cli"


def master_uri() -> str:
    """The master a tool talks to: ``ROS_MASTER_URI`` (or roscore's default)."""
    return master_uri_from_env()


def require_master(uri: str) -> None:
    """Raise ``MasterUnreachable`` (a user error: one line, exit 2) unless ``uri`` answers."""
    if not master_is_up(uri, timeout=2.0):
        raise MasterUnreachable(f"cannot contact the master at {uri} (is it running? "
                                "check ROS_MASTER_URI)")


def start_cli_node() -> ModuleType:
    """This process as an anonymous node (as rostopic does), without signal handlers, on
    wall time even under /use_sim_time (rostopic pub's default), so ``topic pub -r`` can be
    the /clock publisher itself. Returns the node API (``orchestra.node``)."""
    import orchestra.node as rospy  # the runtime only for tools that become a node
    require_master(master_uri())
    rospy.init_node(CLI_NODE, argv=[], anonymous=True, disable_signals=True,
                    disable_rosout=True, disable_rostime=True)
    if threading.current_thread() is threading.main_thread():
        signal.signal(signal.SIGINT, _interrupt_once)
    return rospy


_interrupted = False


def _interrupt_once(signum, frame) -> None:
    """A tool's SIGINT: the first raises KeyboardInterrupt (the tool's loop ends and its
    node unregisters), later ones are ignored. A second KeyboardInterrupt would land inside
    the unwinding of the first, e.g. in the middle of ``Condition.wait`` re-taking its lock
    ("release unlocked lock") or of the node's shutdown ("cannot join thread before it is
    started"): a traceback instead of the clean exit rostopic gives."""
    global _interrupted
    if _interrupted:
        return
    _interrupted = True
    raise KeyboardInterrupt


def stop_cli_node(reason: str) -> None:
    """End the tool's node (unregisters it from the master)."""
    from orchestra.node import runtime
    runtime.reset(reason)


def wait_for_topic(path: str) -> tuple[str, list[str]]:
    """Poll the master until ``path`` or a prefix of it is a known topic, as rostopic echo
    and rqt_plot wait for the topic's type: only then can ``/cmd_vel/linear/x`` be split
    into topic and fields. Returns what ``split_field_path`` makes of it."""
    from orchestra.node import introspect  # only for the tools that wait

    while True:
        topics = introspect.system_state(master_uri()).topics
        topic, fields = split_field_path(path, topics)
        if topic in topics:
            return topic, fields
        time.sleep(0.1)


def split_field_path(name: str, topics: list[str]) -> tuple[str, list[str]]:
    """``/turtle1/pose/x`` -> (``/turtle1/pose``, ``["x"]``) when only the prefix is a topic
    (rostopic echo's field selection); a name that is a topic is returned whole."""
    if name in topics:
        return name, []
    parts = name.split("/")
    for cut in range(len(parts) - 1, 1, -1):
        prefix = "/".join(parts[:cut])
        if prefix in topics:
            return prefix, parts[cut:]
    return name, []
