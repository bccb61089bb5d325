"""Package discovery (catkin/rospack style), package manifests, executables and scaffolding.

The public entry points other areas use are re-exported here so that callers do not depend on
module layout: ``find_package(name) -> str`` (the package directory, or ``PackageNotFound``).
"""
from orchestra.packages.index import PackageNotFound, find_package, get_index

__all__ = ["PackageNotFound", "find_package", "get_index"]
