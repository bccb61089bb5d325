"""Package discovery (catkin/rospack style), package manifests, executables and scaffolding.

The public entry points other areas use are re-exported here so that callers do not depend on
module layout: ``find_package(name) -> str`` (the package directory, or ``PackageNotFound``)
and ``find_executable(pkg, exe) -> str`` (absolute path, or an ``OrchestraError`` saying
why none or which several).
"""
from orchestra.packages.executables import AmbiguousExecutable, ExecutableNotFound, find_executable
from orchestra.packages.index import PackageNotFound, find_package, get_index

__all__ = ["AmbiguousExecutable", "ExecutableNotFound", "PackageNotFound", "find_executable",
           "find_package", "get_index"]
