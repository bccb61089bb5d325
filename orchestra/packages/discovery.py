"""Where packages may live: the ordered list of search roots and the catkin prefixes.

rospack only reads ROS_PACKAGE_PATH, which catkin's ``setup.bash`` fills from the sourced
workspaces. orchestra must also work when nothing was sourced (no ROS install at all), so it
adds what ``setup.bash`` would have added: the ``share/`` (or source spaces) of catkin
prefixes on CMAKE_PREFIX_PATH, the catkin workspace the user is standing in, and the demo
packages bundled with orchestra. Earlier roots shadow later ones, exactly as rospack's
"first found wins".

Everything here is a pure function of the environment and the current directory, so the
index can key its in-process cache on the result.
"""
from __future__ import annotations

import os
import sys
from collections.abc import Mapping
from dataclasses import dataclass


#: orchestra's own demo packages: ``packages/`` at the repository root
def _bundled_packages_dir() -> str:
    """The demo packages shipped with orchestra: the repository's ``packages/`` in a source or
    editable install, else the copy a wheel installs under ``<prefix>/share/orchestra``."""
    source = os.path.join(os.path.dirname(os.path.dirname(os.path.dirname(
        os.path.abspath(__file__)))), "packages")
    if os.path.isdir(source):
        return source
    return os.path.join(sys.prefix, "share", "orchestra", "packages")


BUNDLED_PACKAGES = _bundled_packages_dir()

#: the file catkin drops at the top of every devel and install space
CATKIN_MARKER = ".catkin"

#: files that mark a directory as the root of a catkin workspace (catkin_make,
#: catkin_init_workspace's top-level CMakeLists.txt in src/, catkin_tools)
WORKSPACE_MARKERS = (".catkin_workspace", ".catkin_tools", os.path.join("src", "CMakeLists.txt"))


@dataclass(frozen=True)
class SearchRoot:
    """One directory that is crawled for packages, and why it is on the list."""

    path: str
    origin: str  # "ROS_PACKAGE_PATH", "CMAKE_PREFIX_PATH", "workspace" or "bundled"


def _split(value: str | None) -> list[str]:
    return [entry for entry in (value or "").split(os.pathsep) if entry]


def _normal(path: str) -> str:
    return os.path.normpath(os.path.abspath(path))


def catkin_workspace(cwd: str) -> str | None:
    """The catkin workspace containing ``cwd``.

    The nearest ancestor whose ``src/`` sits next to a workspace marker wins; without any
    marker (a workspace made by hand, no ROS installed), standing inside a directory named
    ``src`` makes its parent the workspace, so ``mkdir -p ws/src && cd ws/src &&
    orchestra create-pkg demo`` is usable at once; so does standing in ``ws`` itself when
    ``ws/src`` holds a package (``ws/src/demo/package.xml``), the usual place to run from. A
    ``src/`` that is merely *below* an ancestor is not enough: ``~/src`` is common and
    crawling it from anywhere in the home directory would be slow and surprising.
    """
    start = _normal(cwd)
    directory = start
    fallback = None
    while True:
        if os.path.isdir(os.path.join(directory, "src")):
            for marker in WORKSPACE_MARKERS:
                if os.path.exists(os.path.join(directory, marker)):
                    return directory
            if directory == start and _holds_package(os.path.join(directory, "src")):
                fallback = directory
        parent = os.path.dirname(directory)
        if fallback is None and os.path.basename(directory) == "src" and parent != directory:
            fallback = parent
        if parent == directory:
            return fallback
        directory = parent


def _holds_package(src: str) -> bool:
    """``src/package.xml`` or ``src/<pkg>/package.xml`` exists (one level, no crawl)."""
    if os.path.isfile(os.path.join(src, "package.xml")):
        return True
    try:
        entries = os.scandir(src)
    except OSError:
        return False
    with entries:
        return any(entry.is_dir() and os.path.isfile(os.path.join(entry.path, "package.xml"))
                   for entry in entries)


def _catkin_source_spaces(prefix: str) -> list[str]:
    """The source directories a devel space's ``.catkin`` marker lists (empty for installs)."""
    try:
        with open(os.path.join(prefix, CATKIN_MARKER), encoding="utf-8") as fh:
            content = fh.read()
    except OSError:
        return []
    return [_normal(p) for p in content.split(";") if p.strip()]


def catkin_prefixes(environ: Mapping[str, str], cwd: str) -> list[str]:
    """Catkin devel/install spaces in priority order: CMAKE_PREFIX_PATH, then the cwd workspace.

    Only prefixes carrying catkin's ``.catkin`` marker count: CMAKE_PREFIX_PATH routinely holds
    ``/usr/local`` or a conda env, whose ``share/`` and ``lib/`` are not package trees.
    """
    prefixes: list[str] = []
    candidates = list(_split(environ.get("CMAKE_PREFIX_PATH")))
    workspace = catkin_workspace(cwd)
    if workspace is not None:
        candidates += [os.path.join(workspace, "devel"), os.path.join(workspace, "install")]
    for candidate in candidates:
        prefix = _normal(candidate)
        if prefix not in prefixes and os.path.isfile(os.path.join(prefix, CATKIN_MARKER)):
            prefixes.append(prefix)
    return prefixes


def current_directory() -> str:
    """The cwd, or ``/`` when it was deleted under us (no workspace then, rather than a crash)."""
    try:
        return os.getcwd()
    except OSError:
        return "/"


def search_roots(environ: Mapping[str, str] | None = None, cwd: str | None = None) -> list[SearchRoot]:
    """The directories crawled for packages, in priority order, each listed once."""
    env = os.environ if environ is None else environ
    here = current_directory() if cwd is None else cwd
    roots: list[SearchRoot] = []
    seen: set[str] = set()

    def add(path: str, origin: str) -> None:
        path = _normal(path)
        if path not in seen:
            seen.add(path)
            roots.append(SearchRoot(path, origin))

    for entry in _split(env.get("ROS_PACKAGE_PATH")):
        add(entry, "ROS_PACKAGE_PATH")
    for prefix in _split(env.get("CMAKE_PREFIX_PATH")):
        prefix = _normal(prefix)
        if not os.path.isfile(os.path.join(prefix, CATKIN_MARKER)):
            continue
        sources = _catkin_source_spaces(prefix)
        for source in sources:
            add(source, "CMAKE_PREFIX_PATH")
        add(os.path.join(prefix, "share"), "CMAKE_PREFIX_PATH")
    workspace = catkin_workspace(here)
    if workspace is not None:
        add(os.path.join(workspace, "src"), "workspace")
    add(BUNDLED_PACKAGES, "bundled")
    return roots


def search_path(environ: Mapping[str, str] | None = None, cwd: str | None = None) -> list[str]:
    """Just the paths of :func:`search_roots` (kept for callers that only need the list)."""
    return [root.path for root in search_roots(environ, cwd)]
