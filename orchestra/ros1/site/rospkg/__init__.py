"""rospkg for orchestra's ROS 1 layer: ``RosPack`` over orchestra's package index and
dependency graph (the same answers as ``orchestra pkg find|list|deps``)."""
from __future__ import annotations

import builtins
import os
from collections.abc import Mapping

from orchestra.packages import PackageNotFound, get_index
from orchestra.packages.deps import all_packages_graph, build_graph
from orchestra.rosdirs import log_dir_root, ros_home

__all__ = ["ResourceNotFound", "RosPack", "get_log_dir", "get_ros_home",
           "get_ros_package_path"]


class ResourceNotFound(Exception):
    """A package that is not on the package path."""

    def __init__(self, msg: str, ros_paths: builtins.list[str] | None = None):
        super().__init__(msg)
        self.ros_paths = ros_paths


class RosPack:
    """rospkg.RosPack(): package paths and dependencies. ``ros_paths`` (a list of roots)
    is accepted for rospkg's signature; the search path is orchestra's (ROS_PACKAGE_PATH,
    CMAKE_PREFIX_PATH, the workspace, the bundled packages)."""

    def __init__(self, ros_paths: list[str] | None = None):
        self.ros_paths = ros_paths

    def list(self) -> builtins.list[str]:
        return get_index().names()

    def get_path(self, name: str) -> str:
        try:
            return get_index().find(name)
        except PackageNotFound:
            raise ResourceNotFound(name) from None

    def _known(self, name: str) -> None:
        self.get_path(name)

    def get_depends(self, name: str, implicit: bool = True) -> builtins.list[str]:
        """What ``name`` depends on: all of it (``implicit``) or only its direct entries."""
        self._known(name)
        graph = build_graph([name])
        return graph.transitive(name) if implicit else graph.direct(name)

    def get_depends_on(self, name: str, implicit: bool = True) -> builtins.list[str]:
        """The packages that depend on ``name`` (directly unless ``implicit``)."""
        self._known(name)
        graph = all_packages_graph()
        if name not in graph.graph:
            return []
        if implicit:
            return graph.dependents(name)
        return sorted(graph.graph.predecessors(name))


def get_ros_home(env: Mapping[str, str] | None = None) -> str:
    """``$ROS_HOME``, else ``~/.ros``."""
    return ros_home(env)


def get_log_dir(env: Mapping[str, str] | None = None) -> str:
    """``$ROS_LOG_DIR``, else ``$ROS_HOME/log``."""
    return log_dir_root(dict(env) if env is not None else None)


def get_ros_package_path(env: Mapping[str, str] | None = None) -> str | None:
    return (os.environ if env is None else env).get("ROS_PACKAGE_PATH")
