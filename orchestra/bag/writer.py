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

import logging
import os
from dataclasses import dataclass, field

from orchestra.bag import chunkcodec
from orchestra.bag.records import (
    MAGIC,
    U32,
    ChunkInfo,
    Connection,
    Op,
    encode_bag_header,
    encode_index,
    encode_message,
    encode_record,
    op_field,
)

log = logging.getLogger(__name__)

#: rosbag record's default chunk size
DEFAULT_CHUNK_SIZE = 768 * 1024


class BagWriteError(Exception):
    """Writing the bag failed (the disk is full, the folder is gone...)."""


@dataclass
class _OpenChunk:
    data: bytearray = field(default_factory=bytearray)
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
        return self._good_end + len(self._chunk.data)

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
        """Append one message (``stamp`` in ns); a full chunk goes to disk at once."""
        if self.failed is not None:
            raise BagWriteError(f"{self.path}: {self.failed.strerror or self.failed}")
        chunk = self._chunk
        if conn.id not in self._in_file and conn.id not in chunk.entries:
            chunk.data += conn.encode()
        chunk.entries.setdefault(conn.id, []).append((stamp, len(chunk.data)))
        chunk.data += encode_message(conn.id, stamp, data)
        chunk.start = stamp if chunk.start < 0 else min(chunk.start, stamp)
        chunk.end = max(chunk.end, stamp)
        self.messages += 1
        if len(chunk.data) >= self.chunk_size:
            self.flush_chunk()

    def flush_chunk(self) -> None:
        """Write the open chunk and its index records in one go."""
        chunk = self._chunk
        if not chunk.entries:
            return
        raw = bytes(chunk.data)
        body = chunkcodec.compress(self.compression, raw)
        out = [encode_record({**op_field(Op.CHUNK), "compression": self.compression.encode(),
                              "size": U32.pack(len(raw))}, body)]
        out += [encode_index(cid, entries) for cid, entries in chunk.entries.items()]
        blob = b"".join(out)
        try:
            self._write(blob)
        except OSError as exc:
            self._fail(exc)
        self._infos.append(ChunkInfo(self._good_end, chunk.start, chunk.end,
                                     {cid: len(e) for cid, e in chunk.entries.items()}))
        self._in_file.update(chunk.entries)
        self._good_end += len(blob)
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
        assert self._fd is not None
        kept = [c for c in self.connections if c.id in self._in_file]
        index = b"".join([c.encode() for c in kept] + [i.encode() for i in self._infos])
        header = encode_bag_header(self._good_end, len(kept), len(self._infos))
        try:
            os.ftruncate(self._fd, self._good_end)
            os.lseek(self._fd, self._good_end, os.SEEK_SET)
            self._write(index)
            os.lseek(self._fd, len(MAGIC), os.SEEK_SET)
            self._write(header)
        except OSError as exc:
            if self.failed is None:
                self.failed = exc
            log.error("%s: cannot write the index (%s); `orchestra bag reindex` repairs it",
                      self.path, exc)

    def _write(self, blob: bytes) -> None:
        assert self._fd is not None
        view = memoryview(blob)
        while view:
            n = os.write(self._fd, view)
            view = view[n:]

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
