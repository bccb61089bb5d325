"""roslib.packages: package directories from orchestra's package index."""
from __future__ import annotations

import os

from orchestra.packages import (
    AmbiguousExecutable,
    ExecutableNotFound,
    PackageNotFound,
    find_executable,
    find_package,
)
from orchestra.packages.index import PackageIndex

__all__ = ["InvalidROSPkgException", "ROSPkgException", "find_node", "get_pkg_dir"]


class ROSPkgException(Exception):
    """Base of roslib's package errors."""


class InvalidROSPkgException(ROSPkgException):
    """No such package on the package path."""


def get_pkg_dir(package: str, required: bool = True, ros_root: str | None = None,
                ros_package_path: str | None = None) -> str | None:
    """The directory of ``package``; a missing one is InvalidROSPkgException, or None when
    not ``required``. ``ros_package_path`` searches those roots instead of the usual path."""
    try:
        if ros_package_path is None:
            return find_package(package)
        roots = [p for p in ros_package_path.split(os.pathsep) if p]
        return PackageIndex.build(roots).find(package)
    except PackageNotFound as exc:
        if required:
            raise InvalidROSPkgException(str(exc)) from None
        return None


def find_node(pkg: str, node_type: str, rospack: object = None) -> list[str]:
    """The executable ``node_type`` of ``pkg`` as a one-element list ([] if none)."""
    try:
        return [find_executable(pkg, node_type)]
    except (ExecutableNotFound, AmbiguousExecutable, PackageNotFound):
        return []
