"""The package index: which package directory answers to which name.

Built once per process (``get_index()``), so ``$(find pkg)`` costs a dict lookup; rospack's
rules: the search path is ROS_PACKAGE_PATH then CMAKE_PREFIX_PATH ``share/`` dirs then the
packages bundled with orchestra; a directory holding ``package.xml`` (or a legacy
``manifest.xml``) is a package and is not descended into; ``CATKIN_IGNORE`` prunes a tree;
the first package found under a name wins.
"""
from __future__ import annotations

import os
from dataclasses import dataclass, field

from orchestra.errors import OrchestraError

BUNDLED_PACKAGES = os.path.join(os.path.dirname(os.path.dirname(os.path.dirname(
    os.path.abspath(__file__)))), "packages")


class PackageNotFound(OrchestraError):
    """A package name that no directory on the search path answers to."""

    def __init__(self, name: str):
        super().__init__(f"package '{name}' not found (searched ROS_PACKAGE_PATH, "
                         "CMAKE_PREFIX_PATH and orchestra's bundled packages)")
        self.name = name


def search_path(environ: dict[str, str] | None = None) -> list[str]:
    """The directories searched for packages, in priority order."""
    env = os.environ if environ is None else environ
    roots: list[str] = []
    for entry in env.get("ROS_PACKAGE_PATH", "").split(os.pathsep):
        if entry:
            roots.append(entry)
    for prefix in env.get("CMAKE_PREFIX_PATH", "").split(os.pathsep):
        if prefix:
            roots.append(os.path.join(prefix, "share"))
    roots.append(BUNDLED_PACKAGES)
    return roots


def _package_name(directory: str) -> str:
    """The package's name: package.xml's <name> when it has one, else the directory name."""
    manifest = os.path.join(directory, "package.xml")
    try:
        with open(manifest, "rb") as fh:
            head = fh.read(4096)
    except OSError:
        return os.path.basename(directory)
    start = head.find(b"<name>")
    end = head.find(b"</name>", start)
    if start >= 0 and end > start:
        name = head[start + 6:end].decode("utf-8", "replace").strip()
        if name:
            return name
    return os.path.basename(directory)


def crawl(root: str) -> list[tuple[str, str]]:
    """(name, directory) for every package below ``root``, in a stable depth-first order."""
    found: list[tuple[str, str]] = []
    if not os.path.isdir(root):
        return found
    stack = [os.path.abspath(root)]
    while stack:
        directory = stack.pop()
        try:
            entries = sorted(os.listdir(directory))
        except OSError:
            continue
        names = set(entries)
        if "CATKIN_IGNORE" in names:
            continue
        if "package.xml" in names or "manifest.xml" in names:
            found.append((_package_name(directory), directory))
            continue
        for entry in reversed(entries):
            if entry.startswith("."):
                continue
            path = os.path.join(directory, entry)
            if os.path.isdir(path):
                stack.append(path)
    return found


@dataclass
class PackageIndex:
    """Package name -> directory, with every shadowed duplicate remembered."""

    packages: dict[str, str] = field(default_factory=dict)
    duplicates: dict[str, list[str]] = field(default_factory=dict)

    @classmethod
    def build(cls, roots: list[str]) -> "PackageIndex":
        index = cls()
        for root in roots:
            for name, directory in crawl(root):
                if name in index.packages:
                    if index.packages[name] != directory:
                        index.duplicates.setdefault(name, []).append(directory)
                    continue
                index.packages[name] = directory
        return index

    def find(self, name: str) -> str:
        try:
            return self.packages[name]
        except KeyError:
            raise PackageNotFound(name) from None


_INDEX: tuple[tuple[str, ...], PackageIndex] | None = None


def get_index() -> PackageIndex:
    """The process-wide index, rebuilt only when the search path itself changes."""
    global _INDEX
    roots = tuple(search_path())
    if _INDEX is None or _INDEX[0] != roots:
        _INDEX = (roots, PackageIndex.build(list(roots)))
    return _INDEX[1]


def find_package(name: str) -> str:
    """The directory of package ``name`` (what ``$(find name)`` and ``rospack find`` return)."""
    return get_index().find(name)
