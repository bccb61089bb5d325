"""Chunk compression of ROS 1 bags: ``none``, ``bz2`` and ``lz4`` (LZ4 frames, which is what
rosbag's roslz4 reads and writes)."""
from __future__ import annotations

import bz2

import lz4.frame

from orchestra.bag.records import BagFormatError

NAMES = ("none", "bz2", "lz4")


def compress(name: str, data: bytes) -> bytes:
    if name == "none":
        return data
    if name == "bz2":
        return bz2.compress(data, 9)
    if name == "lz4":
        # the frame options roslz4 understands: independent 1 MB blocks, a content
        # checksum, and no content size (roslz4 refuses frames that carry one)
        return lz4.frame.compress(data, block_size=lz4.frame.BLOCKSIZE_MAX1MB,
                                  block_linked=False, content_checksum=True, store_size=False)
    raise BagFormatError(f"unknown compression '{name}'")


def decompress(name: str, data: bytes, size: int) -> bytes:
    """The chunk's records; ``size`` is the uncompressed size the chunk header promised."""
    try:
        if name == "none":
            out = data
        elif name == "bz2":
            out = bz2.decompress(data)
        elif name == "lz4":
            out = lz4.frame.decompress(data)
        else:
            raise BagFormatError(f"unknown chunk compression '{name}'")
    except (OSError, ValueError, RuntimeError, EOFError) as exc:
        raise BagFormatError(f"{name} chunk does not decompress: {exc}") from None
    if len(out) != size:
        raise BagFormatError(f"chunk holds {len(out)} bytes, its header says {size}")
    return out
