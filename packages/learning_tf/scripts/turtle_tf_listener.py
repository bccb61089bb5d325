#!/usr/bin/env python3
"""turtle_tf_listener.py: the tutorial's listener: spawns turtle2 at (4, 2) through /spawn and makes it
chase turtle1 at 10 Hz (angular 4.0 * atan2(y, x), linear 0.5 * distance) from tf lookups."""
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.realpath(__file__)), "..", "src"))

from learning_tf_core import nodes  # noqa: E402

import orchestra.node as node  # noqa: E402


def main() -> None:
    node.init_node("turtle_tf_listener")
    nodes.follow("turtle1", "turtle2")


if __name__ == "__main__":
    main()
