"""What to plot: rqt_plot's field specs (``/turtle1/pose/x:y``, ``/scan/ranges[0]``) and the
numeric values they pick out of messages. Pure functions; no plotting, no node."""
from __future__ import annotations

import re
from dataclasses import dataclass, field
from typing import Any

_TOKEN = re.compile(r"([^/\[\]]+)|\[(\d+)\]")


class SpecError(Exception):
    """A field spec that names no topic or no numeric field."""


@dataclass
class Series:
    """One curve: a topic's field, and the (time s, value) points seen so far."""

    topic: str
    path: list[str | int]
    label: str
    times: list[float] = field(default_factory=list)
    values: list[float] = field(default_factory=list)


def parse_path(text: str) -> list[str | int]:
    """``pose/position/x`` or ``ranges[3]`` -> ``["pose", "position", "x"]`` / ``["ranges", 3]``."""
    path: list[str | int] = []
    pos = 0
    text = text.strip("/")
    while pos < len(text):
        if text[pos] == "/":
            pos += 1
            continue
        m = _TOKEN.match(text, pos)
        if not m:
            raise SpecError(f"cannot read field path '{text}'")
        path.append(m.group(1) if m.group(1) is not None else int(m.group(2)))
        pos = m.end()
    return path


def parse_spec(spec: str, topics: list[str]) -> list[Series]:
    """The curves of one rqt_plot argument: the longest known topic that prefixes it, then
    one field per ':'-separated part (``/turtle1/pose/x:y`` is x and y of /turtle1/pose)."""
    first, *more = spec.split(":")
    first = "/" + first.lstrip("/")
    topic = max((t for t in topics if first == t or first.startswith(t.rstrip("/") + "/")),
                key=len, default=None)
    if topic is None:
        raise SpecError(f"{spec}: no such topic" + (
            f" (topics: {', '.join(sorted(topics)[:10])})" if topics else ""))
    rest = first[len(topic):]
    fields = [rest] + more if rest.strip("/") else more
    if not fields:
        raise SpecError(f"{spec}: name a numeric field of {topic} (e.g. {topic}/data)")
    out = []
    for f in fields:
        path = parse_path(f)
        if not path:
            raise SpecError(f"{spec}: empty field name")
        label = topic + "/" + "/".join(str(p) if isinstance(p, str) else f"[{p}]"
                                       for p in path).replace("/[", "[")
        out.append(Series(topic, path, label))
    return out


def pick(msg: Any, path: list[str | int], label: str) -> float:
    """The number at ``path`` in ``msg`` (times and durations as seconds)."""
    value = msg
    for step in path:
        try:
            if isinstance(step, int):
                value = value[step]
            elif step.startswith("_"):
                raise AttributeError(step)
            else:
                value = getattr(value, step)
        except (AttributeError, IndexError, TypeError):
            raise SpecError(f"{label}: {getattr(msg, '_type', 'the message')} has no field "
                            f"{'/'.join(map(str, path))}") from None
    if hasattr(value, "to_sec"):
        value = value.to_sec()
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise SpecError(f"{label}: not a number ({type(value).__name__})")
    return float(value)
