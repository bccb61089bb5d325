"""roslib for orchestra's ROS 1 layer. ``load_manifest`` (rosbuild's way to put a package's
dependencies on sys.path) has nothing to do: orchestra's ``<pkg>.msg`` modules need no
path, so it is accepted and does nothing, as with catkin."""
from __future__ import annotations

__all__ = ["load_manifest"]


def load_manifest(package_name: str, bootstrap_version: str = "0.7") -> None:
    """Accepted for old rosbuild scripts; nothing to load (see the module docstring)."""
