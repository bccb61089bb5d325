"""Read a ROS 1 bag (format 2.0): its index, its chunks, its messages in time order.

rosbags' ``rosbag1.Reader`` reads indexed bags well, but it keeps only ``callerid`` and
``latching`` of each connection header (play and filter need all of it), renames types and
topics to ROS 2 spellings, and cannot scan an unindexed bag, which ``reindex`` must do. So
the file is read here with ``records``' one spelling of the format.
"""
from __future__ import annotations

import heapq
import os
from collections.abc import Iterable, Iterator
from dataclasses import dataclass

from orchestra.bag import chunkcodec
from orchestra.bag.records import (
    BAG_HEADER_LEN,
    MAGIC,
    U32,
    BagFormatError,
    ChunkInfo,
    Connection,
    Op,
    Record,
    decode_header,
    parse_record,
)


class NotABag(BagFormatError):
    """The file is not a ROS 1 bag at all."""


class BagUnindexed(BagFormatError):
    """The bag has no (usable) index: it was not closed, or its index is damaged."""


@dataclass
class ChunkHeader:
    """A chunk as stored: where its data is, how it is compressed, both sizes."""

    pos: int
    compression: str
    size: int
    data_pos: int
    data_len: int

    @property
    def end(self) -> int:
        return self.data_pos + self.data_len


def read_record(fh, pos: int, limit: int) -> Record:
    """The record at ``pos`` of an open file, its data left unread (``limit``: file size)."""
    fh.seek(pos)
    raw = fh.read(4)
    if len(raw) < 4:
        raise BagFormatError(f"record at byte {pos} cut short")
    (hlen,) = U32.unpack(raw)
    if hlen > limit - pos - 8:
        raise BagFormatError(f"record at byte {pos} runs past the end of the file")
    header = fh.read(hlen)
    raw = fh.read(4)
    if len(header) < hlen or len(raw) < 4:
        raise BagFormatError(f"record at byte {pos} cut short")
    (dlen,) = U32.unpack(raw)
    dpos = pos + 8 + hlen
    if dlen > limit - dpos:
        raise BagFormatError(f"record at byte {pos} runs past the end of the file")
    return Record(decode_header(header), dpos, dlen, dpos + dlen, pos)


def read_data(fh, record: Record) -> bytes:
    fh.seek(record.data_pos)
    data = fh.read(record.data_len)
    if len(data) != record.data_len:
        raise BagFormatError(f"record data at byte {record.data_pos} cut short")
    return data


def read_chunk_header(fh, pos: int, limit: int) -> ChunkHeader:
    rec = read_record(fh, pos, limit)
    if rec.op != Op.CHUNK:
        raise BagFormatError(f"expected a chunk at byte {pos}, found record op {rec.op}")
    return ChunkHeader(pos, rec.text("compression"), rec.u32("size"), rec.data_pos,
                       rec.data_len)


def chunk_records(raw: bytes) -> Iterator[tuple[Record, memoryview]]:
    """Each record of a decompressed chunk with its data."""
    view = memoryview(raw)
    pos = 0
    while pos < len(raw):
        rec = parse_record(raw, pos)
        yield rec, view[rec.data_pos:rec.end]
        pos = rec.end


def open_bag_file(path: str):
    """Open ``path``, check the magic, return (file, bag header record, file size)."""
    try:
        fh = open(path, "rb")
    except IsADirectoryError:
        raise NotABag("is a directory") from None
    try:
        size = os.fstat(fh.fileno()).st_size
        magic = fh.read(len(MAGIC))
        if magic != MAGIC:
            if magic.startswith(b"#ROSBAG V"):
                raise NotABag(f"bag version {magic[9:].strip().decode('ascii', 'replace')} "
                              "is not supported (only 2.0)")
            raise NotABag("no '#ROSBAG V2.0' magic at its start")
        try:
            header = read_record(fh, len(MAGIC), size)
            if header.op != Op.BAG_HEADER:
                raise BagFormatError("its first record is not a bag header")
            header.u64("index_pos")
        except BagFormatError as exc:
            raise NotABag(f"bag header damaged: {exc}") from None
    except BaseException:
        fh.close()
        raise
    return fh, header, size


class BagReader:
    """An indexed bag opened for reading. Raises NotABag / BagUnindexed / BagFormatError."""

    def __init__(self, path: str):
        self.path = path
        self._fh, header, self.file_size = open_bag_file(path)
        try:
            index_pos = header.u64("index_pos")
            if index_pos == 0:
                raise BagUnindexed("the bag is not indexed (it was not closed)")
            if index_pos < len(MAGIC) + BAG_HEADER_LEN or index_pos > self.file_size:
                raise BagUnindexed(f"its index position {index_pos} is outside the file")
            try:
                self.connections, self.chunk_infos = self._read_index(
                    index_pos, header.u32("conn_count"), header.u32("chunk_count"))
                self.chunk_headers = [read_chunk_header(self._fh, info.pos, self.file_size)
                                      for info in self.chunk_infos]
            except BagFormatError as exc:
                raise BagUnindexed(f"its index is damaged: {exc}") from None
        except BaseException:
            self._fh.close()
            raise
        self.by_id = {c.id: c for c in self.connections}

    def _read_index(self, pos: int, conn_count: int, chunk_count: int
                    ) -> tuple[list[Connection], list[ChunkInfo]]:
        conns, infos = [], []
        for _ in range(conn_count):
            rec = read_record(self._fh, pos, self.file_size)
            if rec.op != Op.CONNECTION:
                raise BagFormatError(f"expected a connection record at byte {pos}")
            conns.append(Connection.decode(rec, read_data(self._fh, rec)))
            pos = rec.end
        for _ in range(chunk_count):
            rec = read_record(self._fh, pos, self.file_size)
            if rec.op != Op.CHUNK_INFO:
                raise BagFormatError(f"expected a chunk info record at byte {pos}")
            infos.append(ChunkInfo.decode(rec, read_data(self._fh, rec)))
            pos = rec.end
        return conns, infos

    def close(self) -> None:
        self._fh.close()

    def __enter__(self) -> BagReader:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    # --- summary ----------------------------------------------------------------------------

    @property
    def message_count(self) -> int:
        return sum(sum(i.counts.values()) for i in self.chunk_infos)

    @property
    def start_time(self) -> int:
        return min((i.start for i in self.chunk_infos), default=0)

    @property
    def end_time(self) -> int:
        return max((i.end for i in self.chunk_infos), default=0)

    def topic_counts(self) -> dict[int, int]:
        """Messages per connection id."""
        counts: dict[int, int] = {}
        for info in self.chunk_infos:
            for cid, n in info.counts.items():
                counts[cid] = counts.get(cid, 0) + n
        return counts

    # --- messages ---------------------------------------------------------------------------

    def read_chunk(self, header: ChunkHeader) -> bytes:
        self._fh.seek(header.data_pos)
        data = self._fh.read(header.data_len)
        if len(data) != header.data_len:
            raise BagFormatError(f"chunk at byte {header.pos} cut short")
        return chunkcodec.decompress(header.compression, data, header.size)

    def _chunk_messages(self, header: ChunkHeader, wanted: set[int] | None,
                        start: int | None, end: int | None
                        ) -> list[tuple[int, int, int, tuple[int, bytes]]]:
        out = []
        for rec, data in chunk_records(self.read_chunk(header)):
            if rec.op != Op.MSG_DATA:
                continue
            cid = rec.u32("conn")
            if wanted is not None and cid not in wanted:
                continue
            stamp = rec.time("time")
            if (start is not None and stamp < start) or (end is not None and stamp > end):
                continue
            out.append((stamp, header.pos, rec.data_pos, (cid, bytes(data))))
        out.sort(key=lambda m: m[:3])
        return out

    def messages(self, topics: Iterable[str] | None = None, start: int | None = None,
                 end: int | None = None) -> Iterator[tuple[Connection, int, bytes]]:
        """(connection, stamp ns, raw bytes) in time order (stable: file order among equal
        stamps), one chunk in memory at a time unless chunks overlap in time."""
        wanted = None
        if topics is not None:
            names = set(topics)
            wanted = {c.id for c in self.connections if c.topic in names}
        order = sorted(zip(self.chunk_infos, self.chunk_headers, strict=True),
                       key=lambda p: p[0].start)
        order = [(i, h) for i, h in order
                 if (start is None or i.end >= start) and (end is None or i.start <= end)
                 and (wanted is None or wanted & set(i.counts))]
        heap: list[tuple[int, int, int, tuple[int, bytes], Iterator]] = []
        next_chunk = 0
        while True:
            while next_chunk < len(order) and (not heap or order[next_chunk][0].start
                                               <= heap[0][0]):
                info, header = order[next_chunk]
                next_chunk += 1
                msgs = iter(self._chunk_messages(header, wanted, start, end))
                self._push(heap, msgs)
            if not heap:
                return
            stamp, _pos, _off, cid_data, it = heapq.heappop(heap)
            cid, data = cid_data
            yield self.by_id[cid], stamp, data
            self._push(heap, it)

    def _push(self, heap: list, it: Iterator) -> None:
        for stamp, pos, off, cid_data in it:
            heapq.heappush(heap, (stamp, pos, off, cid_data, it))
            return
