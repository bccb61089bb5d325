#!/usr/bin/env python3
"""turtle_tf_broadcaster.py: the tutorial's Python broadcaster, the turtle's name in the private
param ~turtle; publishes world -> turtle from /<turtle>/pose."""
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.realpath(__file__)), "..", "src"))

from learning_tf_core import nodes  # noqa: E402

import orchestra.node as node  # noqa: E402


def main() -> None:
    node.init_node("turtle_tf_broadcaster")
    try:
        turtle = str(node.get_param("~turtle"))
    except KeyError:
        node.logfatal("the private parameter ~turtle (the turtle's name) is not set")
        sys.exit(1)
    nodes.broadcast_pose(turtle)


if __name__ == "__main__":
    main()
