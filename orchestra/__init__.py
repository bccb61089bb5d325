"""orchestra: roslaunch-compatible launch and configuration orchestration, without ROS.

Nodes import this package at start-up, so it stays cheap: the Python API
(``orchestra.launch_file``, ``orchestra.LaunchRun``) is imported on first use.
"""
from __future__ import annotations

from typing import Any

__version__ = "0.1.0"

_LAZY = {"launch_file": "orchestra.app.api", "LaunchRun": "orchestra.app.run"}


def __getattr__(name: str) -> Any:
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module 'orchestra' has no attribute {name!r}")
    import importlib

    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted([*globals(), *_LAZY])
