"""diagnostic_aggregator's analyzers, pure: raw /diagnostics statuses in, a tree out.

Rules kept from the real aggregator because robot dashboards depend on them:

* every raw status is claimed by the FIRST analyzer (in configuration order) that matches it;
  unclaimed ones go to ``Other``;
* a GenericAnalyzer matches by ``name`` (exact), ``startswith``, ``contains``, ``regex`` or
  ``expected``; it renames an item to ``<base_path>/<path>/<name minus remove_prefix>``
  (a leading ``:`` and spaces after the prefix go too: a C++ diagnostic updater names its
  tasks ``"<node>: <task>"``);
* an item not updated for ``timeout`` seconds is stale (level 3), an ``expected`` item never
  seen is reported stale as "Missing"; the analyzer's own header status has the worst level
  of its items, except that a mix of stale and fresh items is an Error, and all stale is
  Stale ("All Stale"); ``discard_stale`` drops stale items instead of reporting them.
"""
from __future__ import annotations

import re
from dataclasses import dataclass, field

from orchestra.errors import OrchestraError

OK, WARN, ERROR, STALE = 0, 1, 2, 3
LEVEL_TEXT = {OK: "OK", WARN: "Warning", ERROR: "Error", STALE: "Stale"}


class AnalyzerConfigError(OrchestraError):
    """An analyzers parameter tree the aggregator cannot build."""


@dataclass
class Status:
    """A diagnostic_msgs/DiagnosticStatus without the message class."""

    level: int
    name: str
    message: str = ""
    hardware_id: str = ""
    values: list[tuple[str, str]] = field(default_factory=list)


def join_path(*parts: str) -> str:
    """``/a/b`` from path pieces, whatever slashes they carry."""
    pieces = [p.strip("/") for p in parts if p and p.strip("/")]
    return "/" + "/".join(pieces)


def remove_leading_chaff(name: str, chaff: str) -> str:
    """``name`` with ``chaff`` removed from the start of its last path element, then a
    leading ``:`` and spaces (``"base_manager: Battery"`` -> ``"Battery"``)."""
    if not chaff:
        return name
    cut = name.rfind("/") + 1
    head, tail = name[:cut], name[cut:]
    if tail.startswith(chaff):
        tail = tail[len(chaff):]
    if tail.startswith(":"):
        tail = tail[1:]
    return head + tail.lstrip(" ")


def _as_list(value: object) -> list[str]:
    if value is None:
        return []
    if isinstance(value, (list, tuple)):
        return [str(v) for v in value]
    return [str(value)]


def _combine(levels: list[int]) -> tuple[int, str]:
    """The header level/message for a group of item levels (stale rules above)."""
    if not levels:
        return OK, "OK"
    worst = max(levels)
    all_stale = all(level == STALE for level in levels)
    if all_stale:
        return STALE, "All Stale"
    if worst == STALE:
        return ERROR, LEVEL_TEXT[ERROR]
    return worst, LEVEL_TEXT[worst]


class Analyzer:
    """Common interface: ``match``/``analyze`` claim raw statuses, ``report`` builds output."""

    path: str

    def match(self, name: str) -> bool:
        raise NotImplementedError

    def analyze(self, status: Status, now: float) -> None:
        raise NotImplementedError

    def report(self, now: float) -> list[Status]:
        raise NotImplementedError


class GenericAnalyzer(Analyzer):
    def __init__(self, path: str, base_path: str = "", *, contains=None, startswith=None,
                 name=None, expected=None, regex=None, remove_prefix=None,
                 find_and_remove_prefix=None, timeout: float = 5.0, num_items: int = 0,
                 discard_stale: bool = False):
        if not path:
            raise AnalyzerConfigError("GenericAnalyzer needs a 'path'")
        self.path = join_path(base_path, path)
        self.contains = _as_list(contains)
        self.startswith = _as_list(startswith) + _as_list(find_and_remove_prefix)
        self.names = _as_list(name)
        self.expected = _as_list(expected)
        try:
            self.regex = [re.compile(r) for r in _as_list(regex)]
        except re.error as exc:
            raise AnalyzerConfigError(f"GenericAnalyzer '{path}': bad regex: {exc}") from None
        self.chaff = _as_list(remove_prefix) + _as_list(find_and_remove_prefix)
        self.timeout = float(timeout)
        self.num_items = int(num_items)
        self.discard_stale = bool(discard_stale)
        self.items: dict[str, tuple[Status, float]] = {}

    def match(self, name: str) -> bool:
        return (name in self.names or name in self.expected
                or any(name.startswith(s) for s in self.startswith)
                or any(s in name for s in self.contains)
                or any(r.search(name) for r in self.regex))

    def analyze(self, status: Status, now: float) -> None:
        self.items[status.name] = (status, now)

    def output_name(self, name: str) -> str:
        for chaff in self.chaff:
            stripped = remove_leading_chaff(name, chaff)
            if stripped != name:
                name = stripped
                break
        return join_path(self.path, name)

    def report(self, now: float) -> list[Status]:
        out: list[Status] = []
        for raw_name, (status, seen) in sorted(self.items.items()):
            stale = self.timeout > 0 and now - seen > self.timeout
            if stale and self.discard_stale:
                continue
            out.append(Status(STALE if stale else status.level, self.output_name(raw_name),
                              status.message, status.hardware_id, list(status.values)))
        for expected in self.expected:
            if expected not in self.items:
                out.append(Status(STALE, self.output_name(expected), "Missing"))
        level, message = _combine([s.level for s in out])
        if self.num_items > 0 and len(out) != self.num_items:
            level, message = ERROR, f"Expected {self.num_items}, found {len(out)}"
        if not out and self.timeout > 0 and not self.discard_stale:
            level, message = STALE, "No items"
        header = Status(level, self.path, message,
                        values=[(s.name.rsplit("/", 1)[-1], s.message) for s in out])
        return [header] + out


class AnalyzerGroup(Analyzer):
    """Analyzers under a common path; the group's header is the worst of its members'."""

    def __init__(self, path: str, analyzers: list[Analyzer], base_path: str = ""):
        self.path = join_path(base_path, path)
        self.analyzers = analyzers

    def match(self, name: str) -> bool:
        return any(a.match(name) for a in self.analyzers)

    def analyze(self, status: Status, now: float) -> None:
        for analyzer in self.analyzers:
            if analyzer.match(status.name):
                analyzer.analyze(status, now)
                return

    def report(self, now: float) -> list[Status]:
        reports = [a.report(now) for a in self.analyzers]
        level, message = _combine([r[0].level for r in reports if r])
        header = Status(level, self.path, message)
        return [header] + [s for r in reports for s in r]


def build_analyzer(key: str, spec: object, base_path: str) -> Analyzer:
    """One analyzer from its parameter dict (``type`` picks the class)."""
    if not isinstance(spec, dict):
        raise AnalyzerConfigError(f"analyzer '{key}' is not a dictionary")
    kind = str(spec.get("type", ""))
    short = kind.split("/")[-1]
    if short == "GenericAnalyzer":
        options = {k: v for k, v in spec.items() if k not in ("type", "path")}
        known = {"contains", "startswith", "name", "expected", "regex", "remove_prefix",
                 "find_and_remove_prefix", "timeout", "num_items", "discard_stale"}
        unknown = sorted(set(options) - known)
        if unknown:
            raise AnalyzerConfigError(f"analyzer '{key}': unknown option(s) {', '.join(unknown)}")
        return GenericAnalyzer(str(spec.get("path", "")), base_path, **options)
    if short == "AnalyzerGroup":
        path = str(spec.get("path", ""))
        children = build_analyzers(spec.get("analyzers", {}), join_path(base_path, path))
        return AnalyzerGroup(path, children, base_path)
    raise AnalyzerConfigError(f"analyzer '{key}': unsupported type '{kind}' (supported: "
                              "diagnostic_aggregator/GenericAnalyzer, "
                              "diagnostic_aggregator/AnalyzerGroup)")


def build_analyzers(specs: object, base_path: str = "") -> list[Analyzer]:
    if specs in (None, {}):
        return []
    if not isinstance(specs, dict):
        raise AnalyzerConfigError("'analyzers' must be a dictionary of analyzers")
    # parameter dictionaries come back from the server sorted by key: keep that order
    return [build_analyzer(key, specs[key], base_path) for key in sorted(specs)]


class Aggregator:
    """Routes raw statuses to analyzers and produces one aggregated array per tick."""

    def __init__(self, analyzers: list[Analyzer], base_path: str = "",
                 other_timeout: float = 5.0):
        self.analyzers = analyzers
        self.other = GenericAnalyzer("Other", base_path, regex=".*", timeout=other_timeout,
                                     discard_stale=True)
        self.base_path = base_path

    def add(self, status: Status, now: float) -> None:
        for analyzer in self.analyzers:
            if analyzer.match(status.name):
                analyzer.analyze(status, now)
                return
        self.other.analyze(status, now)

    def report(self, now: float) -> tuple[list[Status], Status]:
        """(every output status, the top-level state)."""
        out: list[Status] = []
        headers: list[int] = []
        for analyzer in self.analyzers:
            statuses = analyzer.report(now)
            headers.append(statuses[0].level)
            out.extend(statuses)
        other = self.other.report(now)
        if len(other) > 1:  # Other appears only while something is unclaimed
            out.extend(other)
            headers.append(other[0].level)
        level, message = _combine(headers)
        return out, Status(level, "toplevel_state", message)
