"""``bag info``: the summary of a bag in rosbag info's layout (text and ``--yaml``).

The figures come from the index only (connections, chunk infos, chunk headers), as rosbag's
do, so info on a large bag reads a few kilobytes. Rounding, widths and the choice of first
and last chunk for start and end follow rosbag info, so the two print the same bytes.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field

from orchestra.bag.reader import BagReader


@dataclass
class TopicSummary:
    topic: str
    type: str
    messages: int
    connections: int
    frequency: float | None = None  # median rate (--freq), None when not computed


@dataclass
class BagSummary:
    """What info prints, computed once from a reader."""

    path: str
    size: int
    start: float = 0.0
    end: float = 0.0
    messages: int = 0
    indexed: bool = False
    #: compression name -> (chunks, uncompressed bytes, compressed bytes), in chunk order
    compression: dict[str, list[int]] = field(default_factory=dict)
    types: list[tuple[str, str]] = field(default_factory=list)
    topics: list[TopicSummary] = field(default_factory=list)

    @property
    def duration(self) -> float:
        return self.end - self.start


def _to_sec(ns: int) -> float:
    return float(ns // 1_000_000_000) + float(ns % 1_000_000_000) / 1e9


def summarize(path: str, reader: BagReader, freq: bool = False) -> BagSummary:
    """The summary; ``freq`` also reads every message stamp for the median rates
    (rosbag info --freq), which means reading the whole bag."""
    s = BagSummary(path=path, size=reader.file_size)
    if not reader.chunk_infos:
        return s
    s.indexed = True
    s.start = _to_sec(reader.chunk_infos[0].start)
    s.end = _to_sec(reader.chunk_infos[-1].end)
    s.messages = reader.message_count
    for header in reader.chunk_headers:
        entry = s.compression.setdefault(header.compression, [0, 0, 0])
        entry[0] += 1
        entry[1] += header.size
        entry[2] += header.data_len
    seen: dict[str, str] = {}
    for conn in reader.connections:
        seen.setdefault(conn.type, conn.md5sum)
    s.types = sorted(seen.items())
    counts = reader.topic_counts()
    for topic in sorted({c.topic for c in reader.connections}):
        conns = [c for c in reader.connections if c.topic == topic]
        s.topics.append(TopicSummary(topic, conns[0].type, sum(counts.get(c.id, 0)
                                                                for c in conns), len(conns)))
    if freq:
        stamps: dict[str, list[float]] = {}
        for conn, stamp, _data in reader.messages():
            stamps.setdefault(conn.topic, []).append(_to_sec(stamp))
        for t in s.topics:
            t.frequency = median_rate(stamps.get(t.topic, []))
    return s


def median_rate(stamps: list[float]) -> float | None:
    """1 / the median gap between consecutive stamps (rosbag's even-length median)."""
    if len(stamps) < 2:
        return None
    gaps = sorted(b - a for a, b in zip(stamps, stamps[1:], strict=False))
    n = len(gaps)
    mid = gaps[n // 2] if n % 2 else (gaps[n // 2 - 1] + gaps[n // 2]) / 2
    return 1.0 / mid if mid > 0.0 else None


def human_rate(freq: float) -> str:
    for suffix in ("Hz", "kHz", "MHz", "GHz", "THz", "PHz", "EHz", "ZHz", "YHz"):
        if freq < 1000.0:
            return f"{freq:.1f} {suffix}"
        freq /= 1000.0
    return "-"


def human_size(size: float) -> str:
    for suffix in ("KB", "MB", "GB", "TB", "PB", "EB", "ZB", "YB"):
        size /= 1024.0
        if size < 1024.0:
            return f"{size:.1f} {suffix}"
    return "-"


def _stamp_text(secs: float) -> str:
    frac = f"{secs - int(secs):.2f}"[1:]
    return time.strftime("%b %d %Y %H:%M:%S", time.localtime(secs)) + frac


def _duration_text(duration: float) -> str:
    secs = duration % 60
    mins = int(duration / 60)
    hrs = int(mins / 60)
    if hrs > 0:
        return f"{hrs}hr {mins % 60}:{int(secs):02d}s ({int(duration)}s)"
    if mins > 0:
        return f"{mins}:{int(secs):02d}s ({int(duration)}s)"
    return f"{duration:.1f}s"


def _ranked(compression: dict[str, list[int]]) -> list[tuple[int, str]]:
    """(chunk count, name), most used first (ties: name descending), as rosbag ranks."""
    return sorted(((v[0], k) for k, v in compression.items()), reverse=True)


def text(s: BagSummary) -> str:
    rows: list[tuple[str, str]] = [("path", s.path), ("version", "2.0")]
    if not s.indexed:
        rows.append(("size", human_size(s.size)))
        return _layout(rows)
    rows.append(("duration", _duration_text(s.duration)))
    rows.append(("start", f"{_stamp_text(s.start)} ({s.start:.2f})"))
    rows.append(("end", f"{_stamp_text(s.end)} ({s.end:.2f})"))
    rows.append(("size", human_size(s.size)))
    rows.append(("messages", str(s.messages)))
    chunks = sum(v[0] for v in s.compression.values())
    parts = []
    for count, name in _ranked(s.compression):
        if name == "none":
            parts.append(f"{name} [{count}/{chunks} chunks]")
        else:
            _, raw, packed = s.compression[name]
            parts.append(f"{name} [{count}/{chunks} chunks; {100.0 * packed / raw:.2f}%]")
    rows.append(("compression", ", ".join(parts)))
    if any(name != "none" for name in s.compression):
        raw = sum(v[1] for v in s.compression.values())
        packed = sum(v[2] for v in s.compression.values())
        raw_t, packed_t = human_size(raw), human_size(packed)
        w = max(len(raw_t), len(packed_t))
        if s.duration > 0:
            raw_r, packed_r = human_size(raw / s.duration), human_size(packed / s.duration)
            rw = max(len(raw_r), len(packed_r))
            rows.append(("uncompressed", f"{raw_t:>{w}} @ {raw_r:>{rw}}/s"))
            rows.append(("compressed", f"{packed_t:>{w}} @ {packed_r:>{rw}}/s "
                                       f"({100.0 * packed / raw:.2f}%)"))
        else:
            rows.append(("uncompressed", f"{raw_t:>{w}}"))
            rows.append(("compressed", f"{packed_t:>{w}}"))
    type_w = max(len(t) for t, _ in s.types)
    for i, (type_, md5) in enumerate(s.types):
        rows.append(("types" if i == 0 else "", f"{type_:<{type_w}} [{md5}]"))
    topic_w = max(len(t.topic) for t in s.topics)
    count_w = max(len(str(t.messages)) for t in s.topics)
    freq_w = max((len(human_rate(t.frequency)) for t in s.topics if t.frequency is not None),
                 default=0)
    for i, t in enumerate(s.topics):
        rate = (f" @ {human_rate(t.frequency):>{freq_w}}" if t.frequency is not None
                else f"   {'':>{freq_w}}")
        line = (f"{t.topic:<{topic_w}}   {t.messages:>{count_w}} "
                f"{'msgs' if t.messages > 1 else 'msg '}{rate} : {t.type:<{type_w}}")
        if t.connections > 1:
            line += f" ({t.connections} connections)"
        rows.append(("topics" if i == 0 else "", line))
    return _layout(rows)


def _layout(rows: list[tuple[str, str]]) -> str:
    width = max(len(name) for name, _ in rows) + 1
    lines = [f"{(name + ':') if name else '':<{width}} {value}" for name, value in rows]
    return "\n".join(lines).rstrip()


def yaml_text(s: BagSummary) -> str:
    out = [f"path: {s.path}", "version: 2.0"]
    if not s.indexed:
        out += [f"size: {s.size}", "indexed: False"]
        return "\n".join(out) + "\n"
    out += [f"duration: {s.duration:.6f}", f"start: {s.start:.6f}", f"end: {s.end:.6f}",
            f"size: {s.size}", f"messages: {s.messages}", "indexed: True",
            f"compression: {_ranked(s.compression)[0][1]}"]
    if any(name != "none" for name in s.compression):
        out.append(f"uncompressed: {sum(v[1] for v in s.compression.values())}")
        out.append(f"compressed: {sum(v[2] for v in s.compression.values())}")
    out.append("types:")
    for type_, md5 in s.types:
        out += [f"    - type: {type_}", f"      md5: {md5}"]
    out.append("topics:")
    for t in s.topics:
        out += [f"    - topic: {t.topic}", f"      type: {t.type}", f"      messages: {t.messages}"]
        if t.connections > 1:
            out.append(f"      connections: {t.connections}")
        if t.frequency is not None:
            out.append(f"      frequency: {t.frequency:.4f}")
    return "\n".join(out) + "\n"
