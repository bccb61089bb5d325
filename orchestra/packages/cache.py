"""The on-disk crawl cache: one small JSON file per search root under ``$ROS_HOME/orchestra``.

Why per root: processes with different ROS_PACKAGE_PATHs (tests, several workspaces) then
never overwrite each other's work. Why atomic: many orchestra processes may start at once
(``orchestra launch`` from scripts, parallel tests), so a file is written to a temporary name
in the same directory and renamed over the old one; a reader sees either the old or the new
file, never half of one. A lost race only costs the loser's next run a re-crawl.

The cache is an optimisation only: an unreadable, corrupt or unwritable cache is ignored
(logged at debug level) and never fails a command — the compat runner even runs orchestra
with HOME unset.
"""
from __future__ import annotations

import json
import os
import zlib
from collections.abc import Mapping

from orchestra import rosdirs
from orchestra.log_setup import logger
from orchestra.packages.crawl import Record

log = logger(__name__)

FORMAT = 2  # 2: package records carry is_metapackage

#: one file per root ever crawled would grow without bound (every test's temporary tree);
#: past MAX_FILES the least recently written files go, down to KEEP_FILES
MAX_FILES = 200
KEEP_FILES = 100


def default_cache_dir(environ: Mapping[str, str] | None = None) -> str | None:
    """Where the index cache lives (``orchestra.rosdirs.cache_dir``)."""
    return rosdirs.cache_dir(environ)


def cache_file(cache_dir: str, root: str) -> str:
    """The cache file of ``root``. Named by a CRC-32 of the path, not a cryptographic hash:
    importing hashlib (OpenSSL) cost every ``$(find)`` process ~3 ms, and two roots that
    share a name only take turns re-crawling, because the file records its root."""
    digest = zlib.crc32(root.encode("utf-8", "surrogateescape"))
    return os.path.join(cache_dir, f"packages-{digest:08x}.json")


def load(cache_dir: str | None, root: str) -> dict[str, Record]:
    """The records saved for ``root``, or an empty dict when there are none usable."""
    if cache_dir is None:
        return {}
    path = cache_file(cache_dir, root)
    try:
        with open(path, encoding="utf-8") as fh:
            doc = json.load(fh)
    except FileNotFoundError:
        return {}
    except (OSError, ValueError) as exc:
        log.debug("ignoring unreadable package cache %s: %s", path, exc)
        return {}
    if not isinstance(doc, dict) or doc.get("format") != FORMAT or doc.get("root") != root:
        return {}
    records = doc.get("records")
    return records if isinstance(records, dict) else {}


def save(cache_dir: str | None, root: str, records: dict[str, Record]) -> bool:
    """Atomically replace the cache file of ``root``; False (and no exception) on failure."""
    if cache_dir is None:
        return False
    import tempfile  # only writers pay for it

    tmp = None
    try:
        os.makedirs(cache_dir, exist_ok=True)
        fd, tmp = tempfile.mkstemp(dir=cache_dir, prefix=".packages-", suffix=".tmp")
        with os.fdopen(fd, "w", encoding="utf-8") as fh:
            json.dump({"format": FORMAT, "root": root, "records": records}, fh,
                      separators=(",", ":"))
        os.replace(tmp, cache_file(cache_dir, root))
        _prune(cache_dir)
        return True
    except OSError as exc:
        log.debug("cannot write package cache in %s: %s", cache_dir, exc)
        if tmp is not None:
            try:
                os.unlink(tmp)
            except OSError:
                pass
        return False


def _prune(cache_dir: str) -> None:
    """Drop the least recently written cache files once there are too many."""
    try:
        names = [n for n in os.listdir(cache_dir) if n.startswith("packages-")]
        if len(names) <= MAX_FILES:
            return
        paths = [os.path.join(cache_dir, n) for n in names]
        aged = sorted(paths, key=lambda p: os.stat(p).st_mtime_ns)
        for path in aged[:len(aged) - KEEP_FILES]:
            os.unlink(path)
    except OSError as exc:  # another process pruning at the same time
        log.debug("cache pruning in %s: %s", cache_dir, exc)
