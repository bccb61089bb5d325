"""Reserve disk blocks ahead of a bag's end, without changing the file's size.

Recording an image stream is mostly the kernel copying into the page cache, and on ext4 a
write past the end of the file also allocates its blocks, page by page: about half of a
large write's cost here (a 0.9 MB write: ~0.3 ms plain, ~0.15 ms into reserved blocks).
``fallocate(2)`` with ``FALLOC_FL_KEEP_SIZE`` reserves the blocks in one call and leaves the
size alone, so a killed recorder's file still ends where its last chunk ends (``bag
reindex`` sees nothing new) and a reader never meets zeros. Closing or reindexing truncates
the file to its end, which gives back what was reserved and not used.

Python has no binding for ``fallocate`` (``os.posix_fallocate`` changes the size), so it
is called through ctypes; where that is not possible (not Linux, no such call, a file
system without it) nothing is reserved and writing works as before.
"""
from __future__ import annotations

import functools
import logging
from collections.abc import Callable

log = logging.getLogger(__name__)

_FALLOC_FL_KEEP_SIZE = 0x01


@functools.cache
def _fallocate() -> Callable[[int, int, int, int], int] | None:
    try:
        import ctypes
        call = ctypes.CDLL(None, use_errno=True).fallocate
    except (OSError, AttributeError, ImportError):
        return None
    call.argtypes = [ctypes.c_int, ctypes.c_int, ctypes.c_int64, ctypes.c_int64]
    call.restype = ctypes.c_int
    return call


def reserve(fd: int, offset: int, length: int) -> bool:
    """Reserve ``length`` bytes of blocks from ``offset`` (the size stays); False when the
    system cannot (callers stop asking) or the disk has no room (writes then meet it)."""
    call = _fallocate()
    if call is None:
        return False
    if call(fd, _FALLOC_FL_KEEP_SIZE, offset, length) != 0:
        import ctypes
        log.debug("cannot reserve blocks: errno %d", ctypes.get_errno())
        return False
    return True
