"""Write a ROS 1 bag chunk by chunk, so that whatever happens the file stays repairable.

rosbags' ``rosbag1.Writer`` writes valid bags, but it keeps only ``callerid``/``latching``
of a connection header, buffers the file (a ``kill -9`` loses more than the last chunk) and
cannot recover from a failed write. Recording needs all three, so this writer:

- writes each chunk and its index records with one unbuffered ``write`` call, after which
  they are the kernel's: a killed recorder loses at most the chunk it was filling, and
  ``bag reindex`` rebuilds the index of what is on disk;
- stores each connection's header as the publisher sent it (as rosbag record does);
- on a failed write (disk full), cuts the file back to the last complete chunk and still
  writes the index of what it holds, so the bag recorded so far stays valid.
"""
from __future__ import annotations

import errno
import logging
import os
from dataclasses import dataclass, field

from orchestra.bag import chunkcodec, preallocate
from orchestra.bag.records import (
    MAGIC,
    U32,
    ChunkInfo,
    Connection,
    Op,
    encode_bag_header,
    encode_header,
    encode_index,
    op_field,
    pack_time,
)

log = logging.getLogger(__name__)

_IOV_MAX = 1024

#: rosbag record's default chunk size
DEFAULT_CHUNK_SIZE = 768 * 1024

#: blocks are reserved this far past the end of the file at a time (``preallocate``)
RESERVE_AHEAD = 16 * 1024 * 1024


class BagWriteError(Exception):
    """Writing the bag failed (the disk is full, the folder is gone...)."""


@dataclass
class _OpenChunk:
    """The chunk being filled: its records as a list of pieces (message payloads are kept
    by reference, not copied into one buffer) and their total length."""

    parts: list = field(default_factory=list)
    length: int = 0
    start: int = -1
    end: int = 0
    entries: dict[int, list[tuple[int, int]]] = field(default_factory=dict)


class BagWriter:
    """A bag being written: add connections, write messages, close (writes the index)."""

    def __init__(self, path: str, compression: str = "none",
                 chunk_size: int = DEFAULT_CHUNK_SIZE):
        if compression not in chunkcodec.NAMES:
            raise ValueError(f"unknown compression {compression!r}")
        self.path = path
        self.compression = compression
        self.chunk_size = chunk_size
        self.connections: list[Connection] = []
        self._by_key: dict[tuple, Connection] = {}
        self._in_file: set[int] = set()  # connections whose record is in a written chunk
        self._chunk = _OpenChunk()
        self._infos: list[ChunkInfo] = []
        self._fd: int | None = None
        self._good_end = 0
        self._reserved = 0  # blocks are reserved up to here (0: not yet, -1: cannot)
        self.messages = 0
        self.failed: OSError | None = None

    # --- life cycle -------------------------------------------------------------------------

    def open(self) -> BagWriter:
        try:
            self._fd = os.open(self.path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o644)
            self._write(MAGIC + encode_bag_header(0, 0, 0))
        except OSError as exc:
            self._abandon()
            raise BagWriteError(f"{self.path}: cannot write: {exc.strerror or exc}") from None
        self._good_end = len(MAGIC) + len(encode_bag_header(0, 0, 0))
        return self

    def __enter__(self) -> BagWriter:
        return self.open()

    def __exit__(self, *exc) -> None:
        self.close()

    @property
    def size(self) -> int:
        """Bytes on disk plus the open chunk: what splitting by size looks at."""
        return self._good_end + self._chunk.length

    def add_connection(self, topic: str, header: dict[str, str]) -> Connection:
        """The connection for ``topic`` with this publisher header (one per distinct
        header, as rosbag keys connections)."""
        full = dict(header)
        full["topic"] = topic
        key = (topic, tuple(sorted(full.items())))
        conn = self._by_key.get(key)
        if conn is None:
            conn = Connection(len(self.connections), topic, full)
            self.connections.append(conn)
            self._by_key[key] = conn
        return conn

    def write(self, conn: Connection, stamp: int, data: bytes | memoryview) -> None:
        """Append one message (``stamp`` in ns); a full chunk goes to disk at once. ``data``
        is kept by reference until its chunk is written, so it must not change (bytes)."""
        if self.failed is not None:
            raise BagWriteError(f"{self.path}: {self.failed.strerror or self.failed}")
        chunk = self._chunk
        if conn.id not in self._in_file and conn.id not in chunk.entries:
            record = conn.encode()
            chunk.parts.append(record)
            chunk.length += len(record)
        chunk.entries.setdefault(conn.id, []).append((stamp, chunk.length))
        header = encode_header({**op_field(Op.MSG_DATA), "conn": U32.pack(conn.id),
                                "time": pack_time(stamp)})
        prefix = U32.pack(len(header)) + header + U32.pack(len(data))
        chunk.parts.append(prefix)
        chunk.parts.append(data)
        chunk.length += len(prefix) + len(data)
        chunk.start = stamp if chunk.start < 0 else min(chunk.start, stamp)
        chunk.end = max(chunk.end, stamp)
        self.messages += 1
        if chunk.length >= self.chunk_size:
            self.flush_chunk()

    def flush_chunk(self) -> None:
        """Write the open chunk and its index records in one go."""
        chunk = self._chunk
        if not chunk.entries:
            return
        if self.compression == "none":
            body = chunk.parts
            body_len = chunk.length
        else:
            packed = chunkcodec.compress(self.compression, b"".join(chunk.parts))
            body, body_len = [packed], len(packed)
        header = encode_header({**op_field(Op.CHUNK), "compression": self.compression.encode(),
                                "size": U32.pack(chunk.length)})
        parts = [U32.pack(len(header)) + header + U32.pack(body_len), *body,
                 b"".join(encode_index(cid, entries) for cid, entries in chunk.entries.items())]
        self._reserve(self._good_end + sum(len(p) for p in parts))
        try:
            self._write_parts(parts)
        except OSError as exc:
            self._fail(exc)
        self._infos.append(ChunkInfo(self._good_end, chunk.start, chunk.end,
                                     {cid: len(e) for cid, e in chunk.entries.items()}))
        self._in_file.update(chunk.entries)
        self._good_end += sum(len(p) for p in parts)
        self._chunk = _OpenChunk()

    def close(self) -> None:
        """Write the last chunk, the index and the final bag header. After a failed write,
        the index of the chunks that made it (the bag stays valid), then the error."""
        if self._fd is None:
            return
        try:
            if self.failed is None:
                try:
                    self.flush_chunk()
                except BagWriteError:
                    pass
            self._write_index()
        finally:
            self._abandon()
        if self.failed is not None:
            kept = sum(sum(i.counts.values()) for i in self._infos)
            raise BagWriteError(f"{self.path}: {self.failed.strerror or self.failed}; "
                                f"the bag holds the {kept} messages written before") from None

    # --- internals --------------------------------------------------------------------------

    def _write_index(self) -> None:
        """Write the index after the last good chunk. When even that does not fit (a disk
        filled to the last page), give up the newest chunks one by one until it does: a
        valid bag with fewer messages beats an unindexed one."""
        assert self._fd is not None
        while True:
            used = {cid for info in self._infos for cid in info.counts}
            kept = [c for c in self.connections if c.id in used]
            index = b"".join([c.encode() for c in kept] + [i.encode() for i in self._infos])
            try:
                os.ftruncate(self._fd, self._good_end)
                os.lseek(self._fd, self._good_end, os.SEEK_SET)
                self._write(index)
                os.lseek(self._fd, len(MAGIC), os.SEEK_SET)
                self._write(encode_bag_header(self._good_end, len(kept), len(self._infos)))
                return
            except OSError as exc:
                if self.failed is None:
                    self.failed = exc
                if exc.errno not in (errno.ENOSPC, errno.EDQUOT) or not self._infos:
                    log.error("%s: cannot write the index (%s); `orchestra bag reindex` "
                              "repairs it", self.path, exc)
                    return
                self._good_end = self._infos.pop().pos

    def _reserve(self, end: int) -> None:
        """Reserve blocks up to past ``end`` (see ``preallocate``); a failure only means
        writes allocate their own (a full disk is met, and handled, by the write)."""
        if self._reserved < 0 or end <= self._reserved:
            return
        assert self._fd is not None
        start = max(self._reserved, self._good_end)
        if preallocate.reserve(self._fd, start, end - start + RESERVE_AHEAD):
            self._reserved = end + RESERVE_AHEAD
        else:
            self._reserved = -1

    def _write(self, blob: bytes) -> None:
        assert self._fd is not None
        view = memoryview(blob)
        while view:
            n = os.write(self._fd, view)
            view = view[n:]

    def _write_parts(self, parts: list) -> None:
        """One gathered write of a chunk's pieces (no joined copy of a large chunk)."""
        assert self._fd is not None
        total = sum(len(p) for p in parts)
        done = 0
        for start in range(0, len(parts), _IOV_MAX):  # writev takes at most IOV_MAX pieces
            group = parts[start:start + _IOV_MAX]
            n = os.writev(self._fd, group)
            done += n
            if n < sum(len(p) for p in group):
                break
        if done < total:  # a short write: finish the rest (or meet the error) plainly
            self._write(b"".join(bytes(p) for p in parts)[done:])

    def _fail(self, exc: OSError) -> None:
        """A chunk did not fit: cut the partial chunk off, remember why, and stop."""
        self.failed = exc
        self._chunk = _OpenChunk()
        try:
            assert self._fd is not None
            os.ftruncate(self._fd, self._good_end)
            os.lseek(self._fd, self._good_end, os.SEEK_SET)
        except OSError:
            pass
        raise BagWriteError(f"{self.path}: {exc.strerror or exc}") from None

    def _abandon(self) -> None:
        if self._fd is not None:
            try:
                os.close(self._fd)
            except OSError:
                pass
            self._fd = None
