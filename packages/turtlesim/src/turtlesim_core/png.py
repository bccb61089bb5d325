"""A minimal PNG encoder (8-bit RGB, no interlace) with zlib and struct only.

Enough to save the turtle canvas and the tf tree drawing without adding an imaging library.
"""
from __future__ import annotations

import os
import struct
import zlib

SIGNATURE = b"\x89PNG\r\n\x1a\n"


def _chunk(kind: bytes, data: bytes) -> bytes:
    return (struct.pack(">I", len(data)) + kind + data
            + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF))


def encode_png(width: int, height: int, rgb: bytes | bytearray) -> bytes:
    """PNG bytes for ``height`` rows of ``width`` RGB pixels (row-major, 3 bytes per pixel)."""
    stride = width * 3
    if len(rgb) != stride * height:
        raise ValueError(f"expected {stride * height} bytes of RGB data, got {len(rgb)}")
    # filter type 0 (None) per row: simplest, and zlib still squeezes the flat background
    raw = b"".join(b"\x00" + bytes(rgb[y * stride:(y + 1) * stride]) for y in range(height))
    header = struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)
    return (SIGNATURE + _chunk(b"IHDR", header) + _chunk(b"IDAT", zlib.compress(raw, 6))
            + _chunk(b"IEND", b""))


def write_png(path: str, width: int, height: int, rgb: bytes | bytearray) -> None:
    """Write atomically (temp file + rename) so a viewer never reads half a picture."""
    data = encode_png(width, height, rgb)
    directory = os.path.dirname(os.path.abspath(path))
    os.makedirs(directory, exist_ok=True)
    tmp = f"{path}.tmp{os.getpid()}"
    with open(tmp, "wb") as fh:
        fh.write(data)
    os.replace(tmp, path)
