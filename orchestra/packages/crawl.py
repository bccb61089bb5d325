"""Crawling one search root for packages, reusing what an earlier crawl learnt when it is fresh.

The rospack rules: a directory holding ``package.xml`` (or a rosbuild ``manifest.xml``) is a
package and is not descended into; ``CATKIN_IGNORE`` prunes a directory and everything below;
``rospack_nosubdirs`` stops the descent below a directory; hidden directories are skipped;
symlinked directories are followed (once: a symlink loop cannot hang the crawl).

Each visited directory leaves a *record* keyed by its path, holding the directory's mtime.
A directory's mtime changes whenever an entry is added, removed or renamed in it, so a later
crawl can trust a record whose mtime still matches and skip listing that directory (and, for
a package, skip re-reading its manifest unless the manifest's own mtime changed). A warm
crawl therefore costs one ``stat`` per directory instead of a listing plus a manifest read.

Records are plain lists so that they serialise to JSON unchanged:
``[mtime_ns, "dir", [child, ...]]``,
``[mtime_ns, "pkg", name, manifest, manifest_mtime_ns, is_metapackage]`` or
``[mtime_ns, "stop"]`` (ignored, or no sub-directories to visit).

Metapackages (``<export><metapackage/></export>``) stop the descent like any package but are
not packages to rospack: ``rospack find`` and roslaunch's ``$(find)`` do not resolve them.
The crawl reports them separately so the index can say why such a name is not found.
"""
from __future__ import annotations

import os
import re
import stat
import time
from dataclasses import dataclass, field

from orchestra.log_setup import logger

log = logger(__name__)

MANIFESTS = ("package.xml", "manifest.xml")
IGNORE_MARKER = "CATKIN_IGNORE"
NOSUBDIRS_MARKER = "rospack_nosubdirs"

#: a change made in the same clock tick as a listing leaves the mtime unchanged; any record
#: younger than this (relative to the crawl's start) is stored as "unknown" so that the next
#: crawl looks again (git's "racily clean" rule)
RACY_WINDOW_NS = 2_000_000_000

Record = list

_COMMENT = re.compile(rb"<!--.*?-->", re.S)
_NAME = re.compile(rb"<name>\s*([^<]*?)\s*</name>")
_METAPACKAGE = re.compile(rb"<export>.*?<metapackage\s*/?>.*?</export>", re.S)


def manifest_name(directory: str, manifest: str) -> str:
    """The name a package answers to: package.xml's ``<name>``, else the directory name."""
    return read_manifest_head(directory, manifest)[0]


def read_manifest_head(directory: str, manifest: str) -> tuple[str, bool]:
    """(name, is_metapackage) of the package in ``directory``.

    This is deliberately a text scan, not a full parse: the crawl reads every manifest on the
    path and only needs these two facts; full parsing (and its errors) happens when a command
    needs the rest of the manifest.
    """
    if manifest == "package.xml":
        try:
            with open(os.path.join(directory, manifest), "rb") as fh:
                text = _COMMENT.sub(b"", fh.read())
        except OSError:
            text = b""
        is_meta = _METAPACKAGE.search(text) is not None
        match = _NAME.search(text)
        if match and match.group(1):
            return match.group(1).decode("utf-8", "replace"), is_meta
        log.warning("%s/package.xml has no <name>; using the directory name", directory)
        return os.path.basename(directory), is_meta
    return os.path.basename(directory), False


@dataclass
class CrawlResult:
    """What a crawl of one root found, and the records a later crawl may reuse."""

    packages: list[tuple[str, str]] = field(default_factory=list)
    metapackages: list[tuple[str, str]] = field(default_factory=list)
    records: dict[str, Record] = field(default_factory=dict)
    changed: bool = False
    listed: int = 0  # directories that had to be listed (0 when the cache was fully fresh)


def _scan(directory: str, mtime_ns: int, racy_after: int) -> Record:
    """List one directory and decide what it is."""
    try:
        with os.scandir(directory) as it:
            entries = {entry.name: entry for entry in it}
    except OSError as exc:
        log.debug("cannot list %s: %s", directory, exc)
        return [-1, "stop"]
    stored_mtime = mtime_ns if mtime_ns < racy_after else -1
    if IGNORE_MARKER in entries:
        return [stored_mtime, "stop"]
    for manifest in MANIFESTS:
        if manifest in entries:
            try:
                manifest_mtime = entries[manifest].stat().st_mtime_ns
            except OSError:
                manifest_mtime = -1
            if manifest_mtime >= racy_after:
                manifest_mtime = -1
            name, is_meta = read_manifest_head(directory, manifest)
            return [stored_mtime, "pkg", name, manifest, manifest_mtime, is_meta]
    if NOSUBDIRS_MARKER in entries:
        return [stored_mtime, "stop"]
    children = []
    for name in sorted(entries):
        if name.startswith("."):
            continue
        try:
            if entries[name].is_dir():  # follows symlinks, like rospack
                children.append(name)
        except OSError:
            continue
    return [stored_mtime, "dir", children]


def _fresh(directory: str, record: Record | None, mtime_ns: int) -> bool:
    if record is None or record[0] != mtime_ns or record[0] < 0:
        return False
    if record[1] == "pkg":
        try:
            # plain concatenation: os.path.join dominated warm crawls in profiles
            return os.stat(directory + os.sep + record[3]).st_mtime_ns == record[4] >= 0
        except OSError:
            return False
    return True


def crawl(root: str, previous: dict[str, Record] | None = None) -> CrawlResult:
    """Every package below ``root`` as (name, directory), in a stable depth-first order.

    ``previous`` are the records of an earlier crawl of the same root; fresh ones are reused.
    """
    previous = previous or {}
    result = CrawlResult()
    racy_after = time.time_ns() - RACY_WINDOW_NS
    visited: set[tuple[int, int]] = set()
    stack = [os.path.normpath(os.path.abspath(root))]
    while stack:
        directory = stack.pop()
        try:
            st = os.stat(directory)
        except OSError:
            continue
        if not stat.S_ISDIR(st.st_mode):
            continue
        identity = (st.st_dev, st.st_ino)
        if identity in visited:
            continue
        visited.add(identity)
        record = previous.get(directory)
        if record is None or not _fresh(directory, record, st.st_mtime_ns):
            record = _scan(directory, st.st_mtime_ns, racy_after)
            result.listed += 1
            result.changed = True
        result.records[directory] = record
        if record[1] == "pkg":
            found = result.metapackages if record[5] else result.packages
            found.append((record[2], directory))
        elif record[1] == "dir":
            prefix = directory if directory.endswith(os.sep) else directory + os.sep
            stack.extend([prefix + child for child in reversed(record[2])])
    if not result.changed and len(result.records) != len(previous):
        result.changed = True
    return result
