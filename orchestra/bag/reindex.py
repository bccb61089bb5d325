"""``bag reindex``: rebuild the index of a bag that was not closed (a killed recorder, a
full disk) or whose index is damaged, from the chunks that are complete on disk.

The scan walks the records after the bag header: each complete chunk is decompressed and
its connection and message records give the connections and the chunk's index; it stops at
the first record that is cut short or damaged (the chunk being written when the recorder
died). The file is then cut after the last good chunk, the missing per-chunk index records
and the index are appended, and the bag header is rewritten, as rosbag reindex does.
"""
from __future__ import annotations

import logging
import os
import shutil
from dataclasses import dataclass, field

from orchestra.bag import chunkcodec
from orchestra.bag.reader import chunk_records, open_bag_file, read_data, read_record
from orchestra.bag.records import (
    BAG_HEADER_LEN,
    MAGIC,
    BagFormatError,
    ChunkInfo,
    Connection,
    Op,
    encode_bag_header,
    encode_index,
)

log = logging.getLogger(__name__)


@dataclass
class Scan:
    """What the chunks on disk hold."""

    connections: dict[int, Connection] = field(default_factory=dict)
    chunks: list[ChunkInfo] = field(default_factory=list)
    #: per chunk, the index records it lacks on disk (empty when they are all there)
    missing_index: list[bytes] = field(default_factory=list)
    good_end: int = len(MAGIC) + BAG_HEADER_LEN
    problem: str = ""

    @property
    def messages(self) -> int:
        return sum(sum(c.counts.values()) for c in self.chunks)


def scan(path: str) -> Scan:
    """Read every complete chunk of ``path`` (raises NotABag for a non-bag)."""
    fh, _header, size = open_bag_file(path)
    result = Scan()
    pos = result.good_end
    try:
        while pos < size:
            try:
                rec = read_record(fh, pos, size)
                if rec.op != Op.CHUNK:
                    break  # the index section of a bag that was closed
                raw = chunkcodec.decompress(rec.text("compression"), read_data(fh, rec),
                                            rec.u32("size"))
                entries: dict[int, list[tuple[int, int]]] = {}
                for r, data in chunk_records(raw):
                    if r.op == Op.CONNECTION:
                        conn = Connection.decode(r, data)
                        result.connections.setdefault(conn.id, conn)
                    elif r.op == Op.MSG_DATA:
                        entries.setdefault(r.u32("conn"), []).append(
                            (r.time("time"), r.start))
            except BagFormatError as exc:
                result.problem = f"stopped at byte {pos}: {exc}"
                break
            unknown = set(entries) - set(result.connections)
            if unknown:
                result.problem = f"chunk at byte {pos} uses unknown connections {sorted(unknown)}"
                break
            stamps = [t for e in entries.values() for t, _ in e]
            info = ChunkInfo(pos, min(stamps, default=0), max(stamps, default=0),
                             {cid: len(e) for cid, e in entries.items()})
            end, complete = _skip_index_records(fh, rec.end, size, len(entries))
            result.chunks.append(info)
            result.missing_index.append(b"" if complete else b"".join(
                encode_index(cid, e) for cid, e in entries.items()))
            pos = result.good_end = end if complete else rec.end
            if not complete:
                break
    finally:
        fh.close()
    return result


def _skip_index_records(fh, pos: int, size: int, count: int) -> tuple[int, bool]:
    """The end of the ``count`` index data records after a chunk, and whether all are
    there."""
    for _ in range(count):
        try:
            rec = read_record(fh, pos, size)
        except BagFormatError:
            return pos, False
        if rec.op != Op.INDEX_DATA:
            return pos, False
        pos = rec.end
    return pos, True


def reindex(path: str, backup: bool = True) -> Scan:
    """Repair ``path`` in place (after copying it to ``NAME.orig.bag`` unless ``backup`` is
    false) and return what the scan found."""
    result = scan(path)
    if backup:
        root = path[:-4] if path.endswith(".bag") else path
        shutil.copyfile(path, root + ".orig.bag")
    used = {cid for c in result.chunks for cid in c.counts}
    conns = [c for cid, c in sorted(result.connections.items()) if cid in used]
    with open(path, "r+b") as fh:
        fh.truncate(result.good_end)
        fh.seek(result.good_end)
        # a chunk whose index records were lost is the last one kept
        fh.write(b"".join(result.missing_index))
        index_pos = fh.tell()
        fh.write(b"".join([c.encode() for c in conns] + [c.encode() for c in result.chunks]))
        fh.seek(len(MAGIC))
        fh.write(encode_bag_header(index_pos, len(conns), len(result.chunks)))
        fh.flush()
        os.fsync(fh.fileno())
    return result
