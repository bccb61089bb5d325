"""Reading the files a launch file names, following checked-out symlink stubs.

Real ROS packages contain symlinked launch and YAML files. When such a repository is checked
out without symlink support (``core.symlinks=false``, archives, some CI caches), each symlink
becomes a tiny text file holding the link target. roslaunch on a real checkout follows the
link, so we do the same: a short one-line file whose content names an existing file relative
to its own directory is read through.
"""
from __future__ import annotations

import os

_MAX_STUB = 1024
_MAX_HOPS = 8


def _stub_target(path: str, data: bytes) -> str | None:
    if len(data) > _MAX_STUB or b"\n" in data.rstrip(b"\n") or b"<" in data or b":" in data:
        return None
    try:
        target = data.decode("utf-8").strip()
    except UnicodeDecodeError:
        return None
    if not target or target.startswith("#"):
        return None
    candidate = os.path.normpath(os.path.join(os.path.dirname(path), target))
    return candidate if os.path.isfile(candidate) and candidate != os.path.normpath(path) \
        else None


def read_bytes(path: str) -> bytes:
    """The content of ``path``, read through symlink stubs (OSError if unreadable)."""
    for _ in range(_MAX_HOPS):
        with open(path, "rb") as fh:
            data = fh.read()
        target = _stub_target(path, data)
        if target is None:
            return data
        path = target
    return data


def read_text(path: str) -> str:
    """``read_bytes`` decoded as UTF-8 with universal newlines (Python's text mode)."""
    text = read_bytes(path).decode("utf-8")
    return text.replace("\r\n", "\n").replace("\r", "\n")
