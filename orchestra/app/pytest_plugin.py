"""pytest plugin (entry point ``pytest11``): the ``launch`` fixture.

    def test_sim_respawns(launch):
        run = launch("turtlesim", "multisim.launch")
        run.wait_for(topic="/turtlesim1/turtle1/pose")

Each call starts a LaunchRun with its own master on a free port, a fresh run id and
``ROS_HOME`` in the test's tmp directory (logs included), so tests in parallel — pytest-xdist
workers too — share nothing. Every run is stopped at teardown, whatever the test did.
This module is imported by every pytest session once orchestra is installed: it imports
nothing heavy until the fixture is used.
"""
from __future__ import annotations

from collections.abc import Callable, Iterator
from typing import Any

import pytest


@pytest.fixture
def launch(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Callable[..., Any]]:
    """A function ``launch(path_or_pkg, file=None, args=None, **options)`` -> started run."""
    from orchestra.app.api import launch_file

    runs: list[Any] = []

    def start(path_or_pkg: Any, file: str | None = None, args: dict[str, Any] | None = None,
              **options: Any) -> Any:
        options.setdefault("ros_home", str(tmp_path_factory.mktemp("ros_home")))
        run = launch_file(path_or_pkg, file, args=args, **options)
        runs.append(run)
        return run.start()

    yield start
    for run in reversed(runs):
        if run.supervisor is not None:
            run.stop()
