"""diagnostic_aggregator's analyzers, pure: raw /diagnostics statuses in, a tree out.

Rules kept from the real aggregator because robot dashboards depend on them:

* a raw status goes to EVERY analyzer that matches it; statuses no analyzer takes go to
  ``Other`` (reported only while it holds items, which it drops 5 s after their last update);
* a GenericAnalyzer matches by ``name`` (exact), ``startswith``, ``contains``, ``regex``
  (whole name) or ``expected``, and needs at least one of them; it shows an item as
  ``<base_path>/<path>/<name>`` with ``/`` in the name turned into spaces and the first
  matching ``remove_prefix`` cut from its start together with a following ``:`` and spaces
  (a C++ diagnostic updater names its tasks ``"<node>: <task>"``);
* an item not updated for ``timeout`` seconds is stale (level 3); an ``expected`` item is
  listed from the start, as stale "Missing", until it reports;
* an analyzer's header has the worst level of its items, but stale items make it Error
  unless every item is stale (then Stale; an analyzer without items is Stale too);
  ``num_items`` makes a different count an Error ("Expected N, found M");
* a group's header combines its members' headers by the same rule; the top-level state is
  the worst level of everything published, stale counting as Error unless all is stale.
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


def output_name(name: str) -> str:
    """An item name as shown under its analyzer's path: slashes would fake a deeper tree."""
    return name.replace("/", " ")


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


def _combine(levels: list[int], all_stale: bool) -> int:
    """A header level: the worst level, stale meaning Error unless everything is stale."""
    if all_stale:
        return STALE
    worst = max(levels, default=OK)
    return ERROR if worst == STALE else worst


class Analyzer:
    """Common interface: ``match``/``analyze`` take raw statuses, ``report`` builds output
    whose first status is the analyzer's header (named ``path``)."""

    path: str
    nice_name: str

    def match(self, name: str) -> bool:
        raise NotImplementedError

    def analyze(self, status: Status, now: float) -> bool:
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
        self.nice_name = path
        self.path = join_path(base_path, path)
        self.contains = _as_list(contains)
        self.startswith = _as_list(startswith) + _as_list(find_and_remove_prefix)
        self.names = _as_list(name)
        self.expected = _as_list(expected)
        try:
            self.regex = [re.compile(r) for r in _as_list(regex)]
        except re.error as exc:
            raise AnalyzerConfigError(f"GenericAnalyzer '{path}': bad regex: {exc}") from None
        if not (self.contains or self.startswith or self.names or self.expected or self.regex):
            raise AnalyzerConfigError(f"GenericAnalyzer '{path}' has no way to match items "
                                      "(give contains, startswith, name, expected or regex)")
        self.chaff = [output_name(c) for c in
                      _as_list(remove_prefix) + _as_list(find_and_remove_prefix)]
        self.timeout = float(timeout)
        self.num_items = int(num_items)
        self.discard_stale = bool(discard_stale)
        # expected items are listed from the start: stale and "Missing" until they report
        self.items: dict[str, tuple[Status, float | None]] = {
            e: (Status(STALE, e, "Missing"), None) for e in self.expected}

    def match(self, name: str) -> bool:
        return (name in self.names or name in self.expected
                or any(name.startswith(s) for s in self.startswith)
                or any(s in name for s in self.contains)
                or any(r.fullmatch(name) for r in self.regex))

    def analyze(self, status: Status, now: float) -> bool:
        self.items[status.name] = (status, now)
        return True

    def output_name(self, name: str) -> str:
        shown = output_name(name)
        for chaff in self.chaff:
            stripped = remove_leading_chaff(shown, chaff)
            if stripped != shown:
                shown = stripped
                break
        return join_path(self.path, shown)

    def _stale(self, seen: float | None, now: float) -> bool:
        if seen is None:
            return True
        return self.timeout > 0 and now - seen > self.timeout

    def report(self, now: float) -> list[Status]:
        out: list[Status] = []
        header = Status(OK, self.path, "OK")
        levels: list[int] = []
        all_stale = True
        for raw_name in sorted(self.items):
            status, seen = self.items[raw_name]
            stale = self._stale(seen, now)
            if stale and self.discard_stale:
                del self.items[raw_name]
                continue
            level = STALE if stale else status.level
            levels.append(level)
            all_stale = all_stale and level == STALE
            header.values.append((raw_name, status.message))
            out.append(Status(level, self.output_name(raw_name), status.message,
                              status.hardware_id, list(status.values)))
        header.level = _combine(levels, all_stale)
        header.message = LEVEL_TEXT[header.level]
        if self.num_items > 0 and len(self.items) != self.num_items:
            header.level = max(ERROR, header.level)
            header.message = (f"Expected {self.num_items}, found {len(self.items)}" if self.items
                              else f"No items, expected {self.num_items}")
        missing = [e for e in self.expected if e not in self.items]  # dropped as stale
        if missing:
            everything_stale = all(s.level == STALE for s in out) and header.level == STALE
            header.level, header.message = ((STALE, "All Stale") if everything_stale
                                            else (ERROR, "Error"))
            for name in missing:
                out.append(Status(STALE, self.output_name(name), "Missing"))
                header.values.append((name, "Missing"))
        return [header] + out


class AnalyzerGroup(Analyzer):
    """Analyzers under a common path; the group's header combines its members' headers.
    The aggregator's root is a group at ``base_path`` (no header when that is empty)."""

    def __init__(self, path: str, analyzers: list[Analyzer], base_path: str = ""):
        self.nice_name = path
        self.path = join_path(base_path, path) if path else join_path(base_path)
        self.analyzers = analyzers

    def match(self, name: str) -> bool:
        return any(a.match(name) for a in self.analyzers)

    def analyze(self, status: Status, now: float) -> bool:
        taken = False
        for analyzer in self.analyzers:
            if analyzer.match(status.name):
                taken = analyzer.analyze(status, now) or taken
        return taken

    def report(self, now: float) -> list[Status]:
        header = Status(OK, self.path, "OK")
        if not self.analyzers:
            header.level, header.message = ERROR, "No analyzers"
            return [header]
        out: list[Status] = []
        levels: list[int] = []
        for analyzer in self.analyzers:
            statuses = analyzer.report(now)
            out.extend(statuses)
            if statuses and statuses[0].name == analyzer.path:
                levels.append(statuses[0].level)
                header.values.append((analyzer.nice_name, statuses[0].message))
        header.level = _combine(levels, bool(levels) and all(lv == STALE for lv in levels))
        header.message = LEVEL_TEXT[header.level]
        if self.path == "/":
            return out  # the root group of an aggregator without base_path has no header
        return [header] + out


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
    """Routes raw statuses to the analyzers (or Other) and reports the whole tree."""

    def __init__(self, analyzers: list[Analyzer], base_path: str = "",
                 other_timeout: float = 5.0):
        self.root = AnalyzerGroup("", analyzers, base_path)
        self.other = GenericAnalyzer("Other", base_path, regex=".*", timeout=other_timeout,
                                     discard_stale=True)
        self.base_path = base_path

    def add(self, status: Status, now: float) -> None:
        if not (self.root.match(status.name) and self.root.analyze(status, now)):
            self.other.analyze(status, now)

    def report(self, now: float) -> tuple[list[Status], Status]:
        """(every output status, the top-level state)."""
        out = self.root.report(now) if self.root.analyzers else []
        other = self.other.report(now)
        if len(other) > 1:  # Other appears only while something is unclaimed
            out.extend(other)
        levels = [s.level for s in out]
        level = max(levels, default=OK)
        if level == STALE and min(levels) <= ERROR:
            level = ERROR
        return out, Status(level, "toplevel_state", LEVEL_TEXT[level])
