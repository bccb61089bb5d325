"""Finding a package's executable, the way roslaunch's ``<node type=...>`` and rosrun do.

Where roslaunch looks, in order: the package's ``lib/<pkg>`` ("libexec") and ``share/<pkg>``
directories in the first catkin devel/install space that has either, then the whole package
tree (symlinks followed, hidden directories skipped). Debian's own ROS packages count too:
they put ``package.xml`` in ``/usr/share/<pkg>`` and the binaries in ``/usr/lib/<pkg>``
(``/usr/lib/topic_tools/relay``), and Debian's catkin treats ``/usr`` as a workspace without a
``.catkin`` marker. A candidate must be a regular file the user may execute. Several distinct
matches in the same place are an error naming all of them (roslaunch silently takes the first
one it happens to walk into).
"""
from __future__ import annotations

import os
from collections.abc import Mapping

from orchestra.errors import OrchestraError
from orchestra.packages.discovery import CATKIN_MARKER, catkin_prefixes, current_directory
from orchestra.packages.index import find_package

#: prefixes that are catkin install spaces without carrying the ``.catkin`` marker: Debian
#: installs ROS packages straight into ``/usr`` and patches catkin's ``get_workspaces()`` to
#: always append it, which is how roslaunch there finds ``/usr/lib/topic_tools/relay``
SYSTEM_PREFIXES = ("/usr",)


class ExecutableNotFound(OrchestraError):
    """No executable file of that name in the package."""


class AmbiguousExecutable(OrchestraError):
    """Several executables of that name in the package; ``candidates`` lists them."""

    def __init__(self, message: str, candidates: list[str]):
        super().__init__(message)
        self.candidates = candidates


def is_executable(path: str) -> bool:
    """A regular file (symlinks followed) that the current user may execute."""
    return os.path.isfile(path) and os.access(path, os.X_OK)


def libexec_dirs(package: str, environ: Mapping[str, str] | None = None,
                 cwd: str | None = None, package_dir: str | None = None) -> list[str]:
    """``lib/<pkg>`` and ``share/<pkg>`` of the first catkin prefix that has either.

    Besides CMAKE_PREFIX_PATH and the cwd workspace, a package found at
    ``<prefix>/share/<pkg>`` of a catkin prefix brings that prefix along, so pointing only
    ROS_PACKAGE_PATH at ``/opt/ros/noetic/share`` still finds the binaries in ``lib/``;
    so does a package of Debian's found at ``/usr/share/<pkg>`` (:data:`SYSTEM_PREFIXES`).
    """
    env = os.environ if environ is None else environ
    here = current_directory() if cwd is None else cwd
    prefixes = catkin_prefixes(env, here)
    if package_dir is not None:
        share = os.path.dirname(os.path.abspath(package_dir))
        owner = os.path.dirname(share)
        if (os.path.basename(share) == "share" and owner not in prefixes
                and (os.path.isfile(os.path.join(owner, CATKIN_MARKER))
                     or owner in SYSTEM_PREFIXES)):
            prefixes.append(owner)
    for prefix in prefixes:
        found = [d for d in (os.path.join(prefix, "lib", package),
                             os.path.join(prefix, "share", package)) if os.path.isdir(d)]
        if found:
            return found
    return []


def _walk_matches(top: str, exe: str, executable: bool = True) -> list[str]:
    """Executables (or, with ``executable=False``, the other files) named ``exe`` anywhere
    below ``top``, in a stable order."""
    matches: list[str] = []
    seen: set[str] = set()
    for directory, dirs, files in os.walk(top, topdown=True, followlinks=True):
        real = os.path.realpath(directory)
        if real in seen:  # a symlink loop, or a tree reachable twice
            dirs[:] = []
            continue
        seen.add(real)
        dirs[:] = sorted(d for d in dirs if not d.startswith("."))
        if exe in files:
            candidate = os.path.join(directory, exe)
            if is_executable(candidate) == executable:
                matches.append(os.path.abspath(candidate))
    return matches


def _unique(paths: list[str]) -> list[str]:
    """Drop repeats, including one file reached through two routes (symlinks)."""
    unique: list[str] = []
    reals: set[str] = set()
    for path in paths:
        real = os.path.realpath(path)
        if real not in reals:
            reals.add(real)
            unique.append(path)
    return unique


def executable_candidates(package: str, exe: str, environ: Mapping[str, str] | None = None,
                          cwd: str | None = None) -> list[str]:
    """The executables ``exe`` of ``package`` in the first tier that has any.

    The tiers are the catkin libexec dirs, then the package tree. A build product in
    ``devel/lib/<pkg>`` deliberately wins over the source script it was made from (catkin's
    relay scripts have the same name), as in roslaunch; only matches within one tier compete.
    """
    package_dir = find_package(package)
    if os.sep in exe:  # a path relative to the package, as rosrun allows
        candidate = os.path.join(package_dir, exe)
        return [os.path.abspath(candidate)] if is_executable(candidate) else []
    libexec: list[str] = []
    for top in libexec_dirs(package, environ, cwd, package_dir):
        libexec += _walk_matches(top, exe)
    if libexec:
        return _unique(libexec)
    return _unique(_walk_matches(package_dir, exe))


def find_executable(package: str, exe: str) -> str:
    """The absolute path of executable ``exe`` in ``package`` (for ``<node>`` and ``run``).

    Raises ``PackageNotFound``, ``ExecutableNotFound`` or ``AmbiguousExecutable`` (all
    ``OrchestraError``), whose messages say what to fix.
    """
    matches = executable_candidates(package, exe)
    if not matches:
        package_dir = find_package(package)
        plain = [] if os.sep in exe else _walk_matches(package_dir, exe, executable=False)
        if plain:
            raise ExecutableNotFound(
                f"'{exe}' in package '{package}' is not executable: {', '.join(plain)} "
                f"(chmod +x {plain[0]})")
        raise ExecutableNotFound(
            f"cannot find executable '{exe}' in package '{package}' "
            f"({find_package(package)}): the file must exist in the package (or its catkin "
            "lib/ directory) and be executable (chmod +x)")
    if len(matches) > 1:
        listing = ", ".join(matches)
        raise AmbiguousExecutable(
            f"several executables named '{exe}' in package '{package}': {listing}; "
            "remove or rename all but one", matches)
    return matches[0]
