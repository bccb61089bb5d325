#!/usr/bin/env python3
"""turtle_tf2_listener.py: the tf2 tutorial's Python listener. Spawns the turtle named by the
param `turtle` (default turtle2) at (4, 2) and steers it towards turtle1 at 10 Hz from
tf2_ros.Buffer.lookup_transform(turtle, 'turtle1', Time()) (angular 4 * atan2(y, x), linear
0.5 * distance); a failed lookup waits one period and tries again."""
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.realpath(__file__)), "..", "src"))


def main() -> int:
    from turtle_tf2_core import nodes

    import orchestra.node as node

    node.init_node("tf2_turtle")
    nodes.follow("turtle1", str(node.get_param("turtle", "turtle2")).strip("/"))
    return 0


if __name__ == "__main__":
    from orchestra.node.entry import run_main
    run_main(main)
