"""The Python API: ``orchestra.launch_file(...)`` -> a LaunchRun, for tests and tools.

    with orchestra.launch_file("turtlesim", "turtles.launch", args={"x": "1"}) as run:
        run.wait_for(topic="/turtle1/pose", timeout=10)
        run.kill("/sim")

Each run gets its own embedded master on a free port unless ``master`` names one to reuse,
and a fresh run id (its own log directory), so runs in parallel (pytest-xdist workers,
threads) never share a graph. No terminal title and no live view: the caller owns the
terminal.
"""
from __future__ import annotations

import os
from collections.abc import Mapping
from typing import Any

from orchestra.app.options import RunOptions
from orchestra.app.run import LaunchRun
from orchestra.launch.load import load_plan, split_words
from orchestra.supervise.output import Screen


def api_options(master: str | None = None, **overrides: Any) -> RunOptions:
    """The API's RunOptions: a fresh master unless ``master`` is given, no title, no view."""
    values: dict[str, Any] = {"disable_title": True, "status_view": False}
    if master is None:
        values["fresh_master"] = True
    else:
        values["master_uri"] = master
    values.update(overrides)
    return RunOptions.from_kwargs(values)


def launch_file(path_or_pkg: str | os.PathLike[str], file: str | None = None,
                args: Mapping[str, Any] | None = None, master: str | None = None,
                screen: Screen | None = None, **options: Any) -> LaunchRun:
    """A run of a launch file, not started yet (``with`` starts and stops it).

    ``path_or_pkg`` is a launch file path, or a package name with ``file`` the launch file
    in it (as ``orchestra launch PKG FILE``). ``args`` are the file's ``<arg>`` values.
    ``master``: the URI of a master to reuse (default: start one on a free port).
    ``options`` are RunOptions fields (``with_tests=True``, ``sigint_timeout=5``,
    ``ros_home=...``, ``no_rosout=True`` ...). Launch-file mistakes raise OrchestraError
    here, before anything starts.
    """
    words = (str(path_or_pkg),) if file is None else (str(path_or_pkg), file)
    files, _ = split_words(words)
    values = {str(k): str(v) for k, v in (args or {}).items()}
    plan = load_plan(files, values)
    unknown = set(options) - set(RunOptions.__dataclass_fields__)
    if unknown:
        raise TypeError(f"launch_file() got unknown options: {', '.join(sorted(unknown))}")
    return LaunchRun(plan, api_options(master, **options), screen=screen)
