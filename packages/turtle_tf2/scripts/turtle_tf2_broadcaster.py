#!/usr/bin/env python3
"""turtle_tf2_broadcaster.py: the tf2 tutorial's Python broadcaster. The turtle's name is the
private param ~turtle; each /<turtle>/pose is sent as the TransformStamped world -> <turtle>
through tf2_ros.TransformBroadcaster."""
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.realpath(__file__)), "..", "src"))


def main() -> int:
    from turtle_tf2_core import nodes

    import orchestra.node as node

    node.init_node("turtle_tf2_broadcaster")
    try:
        turtle = str(node.get_param("~turtle")).strip("/")
    except KeyError:
        node.logfatal("the private parameter ~turtle (the turtle's name) is not set")
        return 1
    nodes.broadcast(turtle, f"/{turtle}/pose")
    return 0


if __name__ == "__main__":
    from orchestra.node.entry import run_main
    run_main(main)
