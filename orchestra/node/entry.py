"""The ``__main__`` of a node script: turn the node runtime's exceptions into exit codes.

Every node executable ends the same way: a shutdown (Ctrl-C, SIGTERM, the master telling it
to go) is a normal exit 0, and a ROS error such as an unreachable master is one line on
stderr and exit 1 — never a traceback for something that is not a bug in the node.
"""
from __future__ import annotations

import os
import sys
from collections.abc import Callable

from orchestra.node.exceptions import ROSException, ROSInterruptException


def run_main(main: Callable[[], int | None]) -> None:
    """Run a node's ``main()`` and exit with its return code (0 for None)."""
    try:
        code = main()
    except ROSInterruptException:
        code = 0
    except ROSException as exc:
        sys.stderr.write(f"{os.path.basename(sys.argv[0])}: {exc}\n")
        code = 1
    sys.exit(code or 0)
