"""Reading the files a launch file names, following checked-out symlink stubs.

Real ROS packages contain symlinked launch and YAML files. When such a repository is checked
out without symlink support (``core.symlinks=false``, archives, some CI caches), each symlink
becomes a tiny text file holding the link target. roslaunch on a real checkout follows the
link, so we do the same: a short one-line file whose content names an existing file relative
to its own directory is read through.
"""
from __future__ import annotations

import errno
import os
import stat

_MAX_STUB = 1024
# The largest file a launch file may have read (launch, rosparam, textfile, binfile).
MAX_FILE_BYTES = 256 * 2**20
_MAX_HOPS = 8
_PIECE = 2**20


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


def _read_regular(path: str) -> bytes:
    """A regular file's bytes, at most ``MAX_FILE_BYTES``: a launch file naming /dev/zero or a
    FIFO must get an error, not exhaust memory or block forever.

    Read with the raw descriptor calls: opened non-blocking (a FIFO's open does not wait for
    a writer), checked with ``fstat`` of that descriptor, read in one call sized by it (a
    Python file object and a stat by path cost as much as the read of a launch file)."""
    fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK | os.O_CLOEXEC)
    try:
        info = os.fstat(fd)
        if not stat.S_ISREG(info.st_mode):
            raise OSError(errno.EINVAL, "not a regular file", path)
        # one more byte than the stat says shows whether the file grew since (or is a
        # /proc file, size 0); then it is read on, in pieces, up to the limit
        wanted = min(info.st_size, MAX_FILE_BYTES) + 1
        data = os.read(fd, wanted)
        if 0 < len(data) < wanted - 1:  # short of the stat's size: a read may stop early
            data += _read_rest(fd, wanted - len(data))
        if len(data) > info.st_size:
            data += _read_rest(fd, MAX_FILE_BYTES + 1 - len(data))
    finally:
        os.close(fd)
    if len(data) > MAX_FILE_BYTES:
        raise OSError(errno.EFBIG, f"larger than {MAX_FILE_BYTES // 2**20} MiB", path)
    return data


def _read_rest(fd: int, most: int) -> bytes:
    """Up to ``most`` more bytes of ``fd``, until its end (a read may return fewer bytes
    than asked while more follow)."""
    buf = bytearray()
    while len(buf) < most:
        piece = os.read(fd, min(most - len(buf), _PIECE))
        if not piece:
            break
        buf += piece
    return bytes(buf)


def read_bytes(path: str) -> bytes:
    """The content of ``path``, read through symlink stubs (OSError if unreadable)."""
    for _ in range(_MAX_HOPS):
        data = _read_regular(path)
        target = _stub_target(path, data)
        if target is None:
            return data
        path = target
    return data


def read_text(path: str) -> str:
    """``read_bytes`` decoded as UTF-8 with universal newlines (Python's text mode)."""
    text = read_bytes(path).decode("utf-8")
    return text.replace("\r\n", "\n").replace("\r", "\n")
