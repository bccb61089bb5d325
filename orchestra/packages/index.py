"""The package index: which package directory answers to which name.

Built once per process (``get_index()``), so ``$(find pkg)`` costs a dict lookup, and backed by
an on-disk crawl cache (``cache.py``) so that a new process re-validates the previous crawl
with one ``stat`` per directory instead of listing every directory and reading every manifest.

rospack's rules: the roots (``discovery.search_roots``) are crawled in priority order; the
first package found under a name wins and later ones are remembered as shadowed duplicates
(``orchestra pkg list --duplicates``).
"""
from __future__ import annotations

import os
import time
from dataclasses import dataclass, field

from orchestra.errors import OrchestraError
from orchestra.packages import cache
from orchestra.packages.crawl import crawl
from orchestra.packages.discovery import (
    BUNDLED_PACKAGES,
    SearchRoot,
    current_directory,
    search_path,
    search_roots,
)
from orchestra.suggest import did_you_mean

__all__ = ["BUNDLED_PACKAGES", "PackageIndex", "PackageNotFound", "find_package", "get_index",
           "search_path", "reset_index"]

_USE_DEFAULT = object()


class PackageNotFound(OrchestraError):
    """A package name that no directory on the search path answers to."""

    def __init__(self, name: str, metapackage_dir: str | None = None, hint: str = ""):
        if metapackage_dir is not None:
            message = (f"package '{name}' not found: {metapackage_dir} is a metapackage, and "
                       "like rospack (and so roslaunch's $(find)) orchestra does not resolve "
                       "metapackages; name one of the packages it groups instead")
        else:
            message = (f"package '{name}' not found (searched ROS_PACKAGE_PATH, "
                       "CMAKE_PREFIX_PATH, the current catkin workspace and orchestra's "
                       f"bundled packages){hint}")
        super().__init__(message)
        self.name = name


@dataclass
class PackageIndex:
    """Package name -> directory, with every shadowed duplicate remembered."""

    packages: dict[str, str] = field(default_factory=dict)
    duplicates: dict[str, list[str]] = field(default_factory=dict)
    roots: list[SearchRoot] = field(default_factory=list)
    #: package name -> the search root it was found under (``pkg list --origins``)
    origins: dict[str, SearchRoot] = field(default_factory=dict)
    #: directories that had to be listed while building (0 = everything came from the cache)
    listed: int = 0
    #: metapackage name -> directory (first found): not packages to rospack, kept to explain
    metapackages: dict[str, str] = field(default_factory=dict)

    @classmethod
    def build(cls, roots: list[str] | list[SearchRoot], cache_dir=_USE_DEFAULT) -> PackageIndex:
        """Crawl ``roots`` in order; ``cache_dir=None`` disables the disk cache."""
        if cache_dir is _USE_DEFAULT:
            cache_dir = cache.default_cache_dir()
        index = cls()
        for root in roots:
            if not isinstance(root, SearchRoot):
                root = SearchRoot(os.path.normpath(os.path.abspath(root)), "explicit")
            index.roots.append(root)
            previous = cache.load(cache_dir, root.path)
            result = crawl(root.path, previous)
            index.listed += result.listed
            if result.changed:
                cache.save(cache_dir, root.path, result.records)
            for name, directory in result.packages:
                known = index.packages.get(name)
                if known is None:
                    index.packages[name] = directory
                    index.origins[name] = root
                elif known != directory and directory not in index.duplicates.get(name, ()):
                    index.duplicates.setdefault(name, []).append(directory)
            for name, directory in result.metapackages:
                index.metapackages.setdefault(name, directory)
        return index

    def find(self, name: str) -> str:
        try:
            return self.packages[name]
        except KeyError:
            raise PackageNotFound(name, self.metapackages.get(name),
                                  did_you_mean(name, self.packages)) from None

    def __contains__(self, name: str) -> bool:
        return name in self.packages

    def names(self) -> list[str]:
        return sorted(self.packages)


_INDEX: tuple[tuple, PackageIndex] | None = None


def _key() -> tuple:
    env = os.environ
    return (env.get("ROS_PACKAGE_PATH"), env.get("CMAKE_PREFIX_PATH"), env.get("ROS_HOME"),
            current_directory())


def get_index(refresh: bool = False) -> PackageIndex:
    """The process-wide index, rebuilt only when the environment or cwd that define it change."""
    global _INDEX
    key = _key()
    if refresh or _INDEX is None or _INDEX[0] != key:
        _INDEX = (key, PackageIndex.build(search_roots()))
    return _INDEX[1]


def reset_index() -> None:
    """Forget the process-wide index (tests; tools that just created a package)."""
    global _INDEX, _last_miss_refresh
    _INDEX = None
    _last_miss_refresh = float("-inf")


#: a miss re-validates the index (a package may have been created since it was built), at
#: most this often, so code probing many absent names does not re-crawl each time
MISS_REFRESH_INTERVAL = 1.0
_last_miss_refresh = float("-inf")


def find_package(name: str) -> str:
    """The directory of package ``name`` (what ``$(find name)`` and ``rospack find`` return).

    A hit is a dict lookup. A miss first re-validates the index against the disk (cheap with
    a warm cache) in case the package appeared since the index was built, then raises
    ``PackageNotFound``.
    """
    global _last_miss_refresh
    index = get_index()
    directory = index.packages.get(name)
    if directory is not None:
        return directory
    now = time.monotonic()
    if now - _last_miss_refresh >= MISS_REFRESH_INTERVAL:
        _last_miss_refresh = now
        index = get_index(refresh=True)
    return index.find(name)
