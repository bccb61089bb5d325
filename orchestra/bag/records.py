"""The records of a ROS 1 bag, format 2.0: how one record is laid out in bytes.

A record is ``u32 header_len, header, u32 data_len, data``; a header is a sequence of
``u32 len, name=value`` fields, one of them ``op`` (the record kind). Everything in this
module is pure: bytes in, values out, so the writer, the reader and reindex share one
spelling of the format.
"""
from __future__ import annotations

import struct
from dataclasses import dataclass, field
from enum import IntEnum

MAGIC = b"#ROSBAG V2.0\n"
#: the bag header record is padded so that it can be rewritten in place when the bag closes
BAG_HEADER_LEN = 4096

U32 = struct.Struct("<I")
U64 = struct.Struct("<Q")
TIME = struct.Struct("<II")


class Op(IntEnum):
    """Record kinds (the ``op`` header field)."""

    MSG_DATA = 0x02
    BAG_HEADER = 0x03
    INDEX_DATA = 0x04
    CHUNK = 0x05
    CHUNK_INFO = 0x06
    CONNECTION = 0x07


class BagFormatError(Exception):
    """The bytes are not what the format says; the message says what is wrong."""


def pack_time(ns: int) -> bytes:
    return TIME.pack(ns // 1_000_000_000, ns % 1_000_000_000)


def unpack_time(raw: bytes) -> int:
    sec, nsec = TIME.unpack(raw)
    return sec * 1_000_000_000 + nsec


def encode_header(fields: dict[str, bytes]) -> bytes:
    """The header bytes (without its length prefix) of ``fields``, in their order."""
    out = bytearray()
    for name, value in fields.items():
        item = name.encode() + b"=" + value
        out += U32.pack(len(item)) + item
    return bytes(out)


def decode_header(raw: bytes | memoryview) -> dict[str, bytes]:
    """The fields of a header; a malformed one raises BagFormatError."""
    fields: dict[str, bytes] = {}
    pos, end = 0, len(raw)
    while pos < end:
        if end - pos < 4:
            raise BagFormatError("header field length cut short")
        (size,) = U32.unpack_from(raw, pos)
        pos += 4
        if size > end - pos:
            raise BagFormatError("header field runs past its header")
        item = bytes(raw[pos:pos + size])
        pos += size
        name, sep, value = item.partition(b"=")
        if not sep:
            raise BagFormatError("header field without '='")
        fields[name.decode("utf-8", "replace")] = value
    return fields


def encode_record(fields: dict[str, bytes], data: bytes | memoryview) -> bytes:
    header = encode_header(fields)
    return b"".join((U32.pack(len(header)), header, U32.pack(len(data)), data))


def op_field(op: Op) -> dict[str, bytes]:
    return {"op": bytes([op])}


@dataclass
class Record:
    """One record read from a file or a chunk: its fields, where its data lies, its end."""

    fields: dict[str, bytes]
    data_pos: int
    data_len: int
    end: int
    start: int = 0

    @property
    def op(self) -> int:
        raw = self.fields.get("op", b"")
        if len(raw) != 1:
            raise BagFormatError("record without a valid 'op' field")
        return raw[0]

    def u32(self, name: str) -> int:
        return _fixed(self.fields, name, U32)

    def u64(self, name: str) -> int:
        return _fixed(self.fields, name, U64)

    def time(self, name: str) -> int:
        raw = self.fields.get(name)
        if raw is None or len(raw) != 8:
            raise BagFormatError(f"record field '{name}' missing or not a time")
        return unpack_time(raw)

    def text(self, name: str) -> str:
        raw = self.fields.get(name)
        if raw is None:
            raise BagFormatError(f"record field '{name}' missing")
        return raw.decode("utf-8", "replace")


def _fixed(fields: dict[str, bytes], name: str, st: struct.Struct) -> int:
    raw = fields.get(name)
    if raw is None or len(raw) != st.size:
        raise BagFormatError(f"record field '{name}' missing or of the wrong size")
    return int(st.unpack(raw)[0])


def parse_record(buf: bytes | memoryview, pos: int) -> Record:
    """The record starting at ``pos`` of an in-memory buffer (a chunk's data)."""
    end = len(buf)
    if end - pos < 4:
        raise BagFormatError(f"record at {pos} cut short")
    (hlen,) = U32.unpack_from(buf, pos)
    hpos = pos + 4
    if hlen > end - hpos - 4:
        raise BagFormatError(f"record header at {pos} runs past the end")
    fields = decode_header(memoryview(buf)[hpos:hpos + hlen])
    (dlen,) = U32.unpack_from(buf, hpos + hlen)
    dpos = hpos + hlen + 4
    if dlen > end - dpos:
        raise BagFormatError(f"record data at {pos} runs past the end")
    return Record(fields, dpos, dlen, dpos + dlen, pos)


@dataclass
class Connection:
    """One connection of a bag: a topic as one publisher sent it, with the full header the
    publisher gave (type, md5sum, message_definition, callerid, latching...)."""

    id: int
    topic: str
    header: dict[str, str] = field(default_factory=dict)

    @property
    def type(self) -> str:
        return self.header.get("type", "")

    @property
    def md5sum(self) -> str:
        return self.header.get("md5sum", "")

    @property
    def definition(self) -> str:
        return self.header.get("message_definition", "")

    @property
    def latching(self) -> bool:
        return self.header.get("latching", "0") == "1"

    @property
    def callerid(self) -> str:
        return self.header.get("callerid", "")

    def encode(self) -> bytes:
        """The connection record: ``conn``/``topic`` in the record header, the connection
        header as its data (``topic`` forced to the bag's topic, as rosbag does)."""
        header = dict(self.header)
        header["topic"] = self.topic
        data = encode_header({k: v.encode() for k, v in sorted(header.items())})
        return encode_record({**op_field(Op.CONNECTION), "conn": U32.pack(self.id),
                              "topic": self.topic.encode()}, data)

    @classmethod
    def decode(cls, record: Record, data: bytes | memoryview) -> Connection:
        header = {k: v.decode("utf-8", "replace") for k, v in decode_header(data).items()}
        topic = record.text("topic")
        if "type" not in header or "md5sum" not in header:
            raise BagFormatError(f"connection {record.u32('conn')} on {topic} lacks type/md5sum")
        return cls(record.u32("conn"), topic, header)


@dataclass
class ChunkInfo:
    """What the index says about one chunk: where it is, its time span, counts per
    connection."""

    pos: int
    start: int
    end: int
    counts: dict[int, int]

    def encode(self) -> bytes:
        data = b"".join(U32.pack(c) + U32.pack(n) for c, n in self.counts.items())
        return encode_record({**op_field(Op.CHUNK_INFO), "ver": U32.pack(1),
                              "chunk_pos": U64.pack(self.pos),
                              "start_time": pack_time(self.start),
                              "end_time": pack_time(self.end),
                              "count": U32.pack(len(self.counts))}, data)

    @classmethod
    def decode(cls, record: Record, data: bytes | memoryview) -> ChunkInfo:
        if record.u32("ver") != 1:
            raise BagFormatError(f"chunk info version {record.u32('ver')} is not supported")
        count = record.u32("count")
        if len(data) != 8 * count:
            raise BagFormatError("chunk info data does not match its count")
        counts = {U32.unpack_from(data, 8 * i)[0]: U32.unpack_from(data, 8 * i + 4)[0]
                  for i in range(count)}
        return cls(record.u64("chunk_pos"), record.time("start_time"),
                   record.time("end_time"), counts)


def encode_index(conn_id: int, entries: list[tuple[int, int]]) -> bytes:
    """The index data record of one connection in one chunk: (time, offset) pairs."""
    data = b"".join(pack_time(t) + U32.pack(off) for t, off in entries)
    return encode_record({**op_field(Op.INDEX_DATA), "ver": U32.pack(1),
                          "conn": U32.pack(conn_id), "count": U32.pack(len(entries))}, data)


def encode_message(conn_id: int, stamp: int, data: bytes | memoryview) -> bytes:
    return encode_record({**op_field(Op.MSG_DATA), "conn": U32.pack(conn_id),
                          "time": pack_time(stamp)}, data)


def encode_bag_header(index_pos: int, conn_count: int, chunk_count: int) -> bytes:
    """The bag header record, padded with spaces to BAG_HEADER_LEN bytes."""
    header = encode_header({**op_field(Op.BAG_HEADER), "index_pos": U64.pack(index_pos),
                            "conn_count": U32.pack(conn_count),
                            "chunk_count": U32.pack(chunk_count)})
    pad = BAG_HEADER_LEN - 4 - len(header) - 4
    return U32.pack(len(header)) + header + U32.pack(pad) + b" " * pad
