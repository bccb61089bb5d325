"""``bag compress`` / ``bag decompress``: rewrite a bag with another chunk compression.

As rosbag does, the bag keeps its name and the original is kept as ``NAME.orig.bag``
(``--output-dir`` writes the result elsewhere instead and leaves the original alone).
"""
from __future__ import annotations

import os

from orchestra.bag.reader import BagReader
from orchestra.bag.rewrite import rewrite


def backup_name(path: str) -> str:
    root = path[:-4] if path.endswith(".bag") else path
    return root + ".orig.bag"


def already(path: str, compression: str) -> bool:
    """Whether every chunk of ``path`` already uses ``compression``."""
    with BagReader(path) as reader:
        return all(h.compression == compression for h in reader.chunk_headers)


def recompress(path: str, compression: str, output_dir: str | None = None,
               force: bool = False) -> str:
    """Rewrite ``path`` with ``compression``; return where the result is."""
    if output_dir is not None:
        dst = os.path.join(output_dir, os.path.basename(path))
        rewrite(path, dst, compression)
        return dst
    backup = backup_name(path)
    if os.path.exists(backup) and not force:
        raise FileExistsError(f"{backup} exists already (use -f to overwrite it)")
    os.replace(path, backup)
    try:
        rewrite(backup, path, compression)
    except BaseException:
        os.replace(backup, path)
        raise
    return path
