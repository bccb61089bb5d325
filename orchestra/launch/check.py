"""``orchestra check``: every problem in a launch tree, with file:line:column, nothing started.

roslaunch-check stops at the first error and only follows the branches the current args take.
A lint should instead list *everything* a user has to fix in one go, so this runs two passes:

1. a static pass over the Entities of every file reachable through ``<include>`` (every
   branch, taken or not): unknown tags and attributes, undeclared and unused args, packages
   that cannot be found, ``file=``/``textfile=``/``binfile=`` that do not exist, include
   cycles (networkx), ``respawn`` together with ``required``. Values are resolved with the
   real substitution code against a static scope (command-line args, then each file's
   ``<arg>`` values/defaults); a value that cannot be resolved statically is simply not
   checked here;
2. the interpreter itself, which resolves the tree exactly as ``orchestra launch`` would
   (``command=`` params are *not* run), so anything it rejects is reported too, plus what
   only a resolved plan shows (duplicate node names).

Problems in a branch that the given args do not take (``if``/``unless`` that resolve to
false) are downgraded to warnings: they are real, but they do not break this launch.
"""
from __future__ import annotations

import ast
import difflib
import logging
import os
from collections.abc import Iterator
from dataclasses import dataclass, field
from typing import Any

import networkx

from orchestra.errors import Location, OrchestraError
from orchestra.launch import evaluate, substitution
from orchestra.launch.entity import Entity

log = logging.getLogger(__name__)

ERROR = "error"
WARNING = "warning"

_CONDITION = frozenset({"if", "unless"})


def _tag_rules() -> tuple[dict[str, frozenset[str]], dict[str, tuple[str, ...]]]:
    """Attributes per tag and children per parent, from the interpreter's own tag rules.

    The attribute sets are the interpreter's (it warns about anything else, as roslaunch
    does); only what the interpreter expresses as code rather than data is spelled out here:
    which tags may hold which children.
    """
    from orchestra.launch import interpreter as rules

    attributes = {
        "launch": frozenset({"deprecated"}),
        "node": frozenset(rules.NODE_ATTRS),
        "test": frozenset(rules.TEST_ATTRS),
        "machine": frozenset(rules.MACHINE_ATTRS),
        "param": frozenset(rules.PARAM_ATTRS),
        "rosparam": frozenset(rules.ROSPARAM_ATTRS),
        "arg": frozenset(rules.ARG_ATTRS),
        "include": frozenset(rules.INCLUDE_ATTRS),
        "group": frozenset(rules.GROUP_ATTRS),
        "remap": frozenset(rules.REMAP_ATTRS),
        "env": frozenset(rules.ENV_ATTRS),
        "master": frozenset({"auto"}),  # defunct; roslaunch ignores it with a warning
    }
    attributes = {tag: names | _CONDITION for tag, names in attributes.items()}
    scope_children = tuple(sorted(rules._TAGS))  # the tags a launch/group body dispatches
    children = {
        "launch": scope_children,
        "group": scope_children,
        "include": ("arg", "env"),
        "node": ("param", "rosparam", "remap", "env"),
        "test": ("param", "rosparam", "remap", "env"),
    }
    return attributes, children


# Attributes without which the interpreter rejects an element. The interpreter states these
# in code (``_req``), not as data; repeated here so that elements in branches the args do not
# take, which the interpreter never reaches, are checked too.
REQUIRED_ATTRIBUTES: dict[str, tuple[str, ...]] = {
    "node": ("pkg", "type", "name"),
    "test": ("pkg", "type", "test-name"),
    "param": ("name",),
    "remap": ("from", "to"),
    "include": ("file",),
    "arg": ("name",),
    "env": ("name", "value"),
    "machine": ("name", "address"),
}

# Static findings the interpreter also raises when it reaches the element: an interpreter
# error on the same line as one of these is the same problem, already reported with its column.
_ALSO_FOUND_BY_INTERPRETER = frozenset({
    "syntax", "missing-package", "missing-file", "include-cycle", "respawn-required",
    "if-unless", "bad-substitution", "missing-attribute", "undeclared-arg",
})

# Names an ``$(eval ...)`` expression may use that are not args.
_EVAL_NAMES = evaluate.NAMES


@dataclass(frozen=True)
class Problem:
    """One finding. ``code`` is a stable short name (for filtering and for tests)."""

    severity: str
    location: Location
    message: str
    code: str

    def __str__(self) -> str:
        return f"{self.location}: {self.severity}: {self.message} [{self.code}]"

    def to_json(self) -> dict[str, Any]:
        return {"file": self.location.file, "line": self.location.line,
                "column": self.location.column, "severity": self.severity,
                "code": self.code, "message": self.message}


@dataclass
class Report:
    """What ``check`` found over one or more top-level files."""

    problems: list[Problem] = field(default_factory=list)
    files: list[str] = field(default_factory=list)

    @property
    def errors(self) -> list[Problem]:
        return [p for p in self.problems if p.severity == ERROR]

    @property
    def warnings(self) -> list[Problem]:
        return [p for p in self.problems if p.severity == WARNING]

    def add(self, problem: Problem) -> None:
        if problem not in self.problems:
            self.problems.append(problem)

    def sorted(self) -> list[Problem]:
        return sorted(self.problems, key=lambda p: (p.location.file, p.location.line or 0,
                                                    p.location.column or 0, p.code))


# ----------------------------------------------------------------------------- locations


class _Sources:
    """File text, read once, to give XML Entities (line only, from lxml) their columns."""

    def __init__(self) -> None:
        self._lines: dict[str, list[str]] = {}

    def lines(self, path: str) -> list[str]:
        if path not in self._lines:
            try:
                with open(path, encoding="utf-8", errors="replace") as fh:
                    self._lines[path] = fh.read().splitlines()
            except OSError:
                self._lines[path] = []
        return self._lines[path]

    def locate(self, entity: Entity, attribute: str | None = None) -> Location:
        """Where ``entity`` (or its ``attribute``) is written, as precisely as known."""
        recorded = getattr(entity, "attribute_locations", None)
        if attribute and recorded and attribute in recorded:
            return recorded[attribute]
        where = entity.location
        if where.line is None or where.column is not None:
            return where
        lines = self.lines(where.file)
        row = where.line - 1
        if not 0 <= row < len(lines):
            return where
        # lxml may give the line where a multi-line start tag *ends*: look back for its start
        for back in range(0, min(row, 30) + 1):
            start = _find_tag(lines[row - back], entity.tag)
            if start >= 0:
                row -= back
                where = Location(where.file, row + 1)
                break
        else:
            return where
        if attribute:
            # the attribute may be on a later line of a multi-line start tag
            for offset in range(0, 20):
                if row + offset >= len(lines):
                    break
                text = lines[row + offset]
                begin = start if offset == 0 else 0
                for quote in ('="', "='", "= ", "="):
                    col = text.find(f"{attribute}{quote}", begin)
                    if col > 0 and not (text[col - 1].isalnum() or text[col - 1] in "_-"):
                        return Location(where.file, where.line + offset, col + 1)
                if ">" in text[begin:]:
                    break
        return Location(where.file, where.line, start + 1)


def _find_tag(line: str, tag: str) -> int:
    """Column (0-based) of ``<tag`` as a whole tag name in ``line``, or -1."""
    begin = 0
    while True:
        col = line.find("<" + tag, begin)
        if col < 0:
            return -1
        after = line[col + 1 + len(tag):col + 2 + len(tag)]
        if not after or after in " \t/>":
            return col
        begin = col + 1


# --------------------------------------------------------------------------- static scope


@dataclass
class _StaticScope:
    """Just enough of a loader scope for ``substitution.resolve``: args and the file."""

    args: dict[str, str]
    filename: str | None


def _try_resolve(value: str | None, scope: _StaticScope) -> str | None:
    """The resolved value, or None when it cannot be resolved without running anything."""
    if value is None:
        return None
    try:
        return substitution.resolve(value, scope)
    except OrchestraError:
        return None
    except Exception:  # a malformed value: the interpreter pass reports it properly
        log.debug("could not resolve %r statically", value, exc_info=True)
        return None


def _is_true(text: str) -> bool | None:
    lowered = text.strip().lower()
    if lowered in ("true", "1"):
        return True
    if lowered in ("false", "0"):
        return False
    return None


def _branch_taken(entity: Entity, scope: _StaticScope) -> bool | None:
    """False when the element's if/unless resolves to "not taken"; None when unknown."""
    for name, want in (("if", True), ("unless", False)):
        raw = entity.get(name)
        if raw is None:
            continue
        value = _try_resolve(raw, scope)
        if value is None:
            return None
        truth = _is_true(value)
        if truth is None:
            return None
        if truth != want:
            return False
    return True


# ----------------------------------------------------------------------------- arg usage


def _arg_references(value: str) -> Iterator[str]:
    """Names of args that ``value`` reads: ``$(arg x)``, and args named inside ``$(eval)``."""
    if "$" not in value:
        return
    stripped = value.strip()
    if stripped.startswith("$(eval ") and stripped.endswith(")"):
        yield from _eval_references(stripped[7:-1])
        return
    try:
        bodies = substitution.collect(value)
    except OrchestraError:
        return
    for body in bodies:
        words = body.split()
        if len(words) == 2 and words[0] == "arg":
            yield words[1]


def _eval_references(expr: str) -> Iterator[str]:
    try:
        tree = ast.parse(expr.strip(), mode="eval")
    except SyntaxError:
        return
    bound = {n.id for n in ast.walk(tree) if isinstance(n, ast.Name)
             and isinstance(n.ctx, ast.Store)}
    called = {id(n.func) for n in ast.walk(tree) if isinstance(n, ast.Call)}
    for node in ast.walk(tree):
        if (isinstance(node, ast.Call) and isinstance(node.func, ast.Name)
                and node.func.id == "arg" and node.args
                and isinstance(node.args[0], ast.Constant)
                and isinstance(node.args[0].value, str)):
            yield node.args[0].value
        elif (isinstance(node, ast.Name) and isinstance(node.ctx, ast.Load)
              and id(node) not in called and node.id not in _EVAL_NAMES
              and node.id not in bound):
            yield node.id


# ------------------------------------------------------------------------------- checker


@dataclass
class _Include:
    """An include edge found statically: who includes what, from where, with which args."""

    source: str
    target: str
    location: Location
    args: dict[str, str]


class Checker:
    """Runs the static pass over a tree of files, then the interpreter (see module doc)."""

    def __init__(self, cli_args: dict[str, str] | None = None):
        self.tag_attributes, self.tag_children = _tag_rules()
        self.cli_args = dict(cli_args or {})
        self.report = Report()
        self.sources = _Sources()
        self.graph = networkx.DiGraph()
        self._checked: set[str] = set()

    # ---------------------------------------------------------------- entry points
    def check(self, path: str) -> Report:
        """Check ``path`` and every file it includes; results accumulate in ``self.report``."""
        path = os.path.abspath(path)
        self.report.files.append(path)
        self.graph.add_node(path)
        parsed = self._check_file(path, dict(self.cli_args), top=True)
        self._report_cycles()
        if parsed:
            self._interpret(path)
        return self.report

    # ---------------------------------------------------------------- helpers
    def _problem(self, severity: str, location: Location, message: str, code: str) -> None:
        self.report.add(Problem(severity, location, message, code))

    def _load(self, path: str) -> Entity | None:
        from orchestra.launch.convert import load_entity

        try:
            return load_entity(path)
        except OrchestraError as exc:
            self._problem(ERROR, exc.location or Location(path), exc.message, "syntax")
            return None

    # ---------------------------------------------------------------- one file
    def _check_file(self, path: str, passed_args: dict[str, str], top: bool) -> bool:
        """Check ``path`` and, depth first, what it includes (a work list, not recursion:
        an include chain may be longer than Python's stack)."""
        pending: list[tuple[str, dict[str, str]]] = []
        ok = self._check_one(path, passed_args, top, pending)
        while pending:
            target, args = pending.pop()
            self._check_one(target, args, False, pending)
        return ok

    def _check_one(self, path: str, passed_args: dict[str, str], top: bool,
                   pending: list[tuple[str, dict[str, str]]]) -> bool:
        if path in self._checked:
            return True
        self._checked.add(path)
        if not os.path.isfile(path):
            self._problem(ERROR, Location(path), "launch file not found", "missing-file")
            return False
        root = self._load(path)
        if root is None:
            return False
        if root.tag != "launch":
            self._problem(ERROR, self.sources.locate(root),
                          f"the root element must be <launch>, not <{root.tag}>",
                          "unknown-tag")
            return True
        scope = _StaticScope(dict(passed_args), path)
        declared: dict[str, Entity] = {}
        used: set[str] = set()
        passes_all = False
        includes: list[_Include] = []
        for entity, parent, taken in self._walk(root, None, scope, True):
            self._check_tag(entity, parent)
            self._check_required(entity, taken)
            self._check_substitutions(entity, taken)
            for value in entity.attributes.values():
                used.update(_arg_references(value))
            if entity.text and entity.tag == "rosparam":
                used.update(_arg_references(entity.text))
            if entity.tag == "arg" and (parent is None or parent.tag != "include"):
                name = entity.get("name")
                if name:
                    declared.setdefault(name, entity)
            if entity.tag == "include" and _is_true(entity.get("pass_all_args") or "") is True:
                passes_all = True
            self._check_resources(entity, scope, taken)
            self._check_node_flags(entity, scope)
            if entity.tag == "include":
                include = self._resolve_include(entity, scope, path, taken)
                if include is not None:
                    includes.append(include)
        self._check_args(path, declared, used, passes_all, set(passed_args), top)
        pending.extend((include.target, include.args) for include in reversed(includes))
        return True

    def _walk(self, entity: Entity, parent: Entity | None, scope: _StaticScope,
              taken: bool) -> Iterator[tuple[Entity, Entity | None, bool]]:
        """Every element of a file, depth first, with whether its branch is known untaken.

        ``<arg>`` values/defaults enter the static scope as they are met (the first value
        wins, so two declarations under exclusive if/unless do not clash).
        """
        branch = _branch_taken(entity, scope)
        taken = taken and branch is not False
        yield entity, parent, taken
        if entity.tag == "arg" and (parent is None or parent.tag != "include"):
            name = entity.get("name")
            if name and name not in scope.args and branch is not False:
                raw = entity.get("value", entity.get("default"))
                resolved = _try_resolve(raw, scope)
                if resolved is not None:
                    scope.args[name] = resolved
        for child in entity.children:
            yield from self._walk(child, entity, scope, taken)

    # ---------------------------------------------------------------- tags and attributes
    def _check_tag(self, entity: Entity, parent: Entity | None) -> None:
        if parent is not None:
            allowed = self.tag_children.get(parent.tag, ())
            if entity.tag not in allowed:
                if entity.tag in self.tag_attributes:
                    message = f"<{entity.tag}> is not allowed inside <{parent.tag}>"
                else:
                    message = f"unknown tag <{entity.tag}>" + _suggest(entity.tag,
                                                                       self.tag_attributes)
                self._problem(ERROR, self.sources.locate(entity),
                              message + " (roslaunch ignores it)", "unknown-tag")
                return
        known = self.tag_attributes.get(entity.tag)
        if known is None:
            return
        for name in entity.attributes:
            if name not in known:
                self._problem(WARNING, self.sources.locate(entity, name),
                              f"unknown attribute '{name}' of <{entity.tag}>"
                              + _suggest(name, known) + " (roslaunch ignores it)",
                              "unknown-attribute")
        if entity.has("if") and entity.has("unless"):
            self._problem(ERROR, self.sources.locate(entity, "unless"),
                          f"<{entity.tag}> has both 'if' and 'unless'", "if-unless")

    def _check_required(self, entity: Entity, taken: bool) -> None:
        missing = [a for a in REQUIRED_ATTRIBUTES.get(entity.tag, ()) if not entity.has(a)]
        if missing:
            severity, note = self._severity(taken)
            names = ", ".join(f"'{a}'" for a in missing)
            self._problem(severity, self.sources.locate(entity),
                          f"<{entity.tag}> is missing required attribute(s) {names}{note}",
                          "missing-attribute")

    def _check_substitutions(self, entity: Entity, taken: bool) -> None:
        """``$(...)`` that can never resolve: unknown command, wrong word count, bad eval."""
        values = list(entity.attributes.items())
        if entity.tag == "rosparam" and entity.text and _is_true(
                entity.get("subst_value") or "") is True:
            values.append(("subst_value", entity.text))
        for name, value in values:
            problem = _substitution_problem(value)
            if problem:
                severity, note = self._severity(taken)
                self._problem(severity, self.sources.locate(entity, name),
                              f"attribute '{name}': {problem}{note}", "bad-substitution")

    # ---------------------------------------------------------------- args
    def _check_args(self, path: str, declared: dict[str, Entity], used: set[str],
                    passes_all: bool, passed: set[str], top: bool) -> None:
        # args handed in (command line for the top file, pass_all_args or <arg> children of
        # the include for others) are visible to $(arg) even when the file does not declare
        # them, as in roslaunch
        known = set(declared) | passed
        for name in sorted(used - known):
            entity = self._first_use(path, name)
            where = self.sources.locate(*entity) if entity else Location(path)
            self._problem(ERROR, where, f"arg '{name}' is used but never declared in this "
                          "file" + (" (nor given on the command line)" if top else ""),
                          "undeclared-arg")
        if passes_all:
            return  # pass_all_args hands every arg on: none is unused here
        for name, entity in declared.items():
            if name not in used:
                self._problem(WARNING, self.sources.locate(entity, "name"),
                              f"arg '{name}' is declared but never used", "unused-arg")

    def _first_use(self, path: str, name: str) -> tuple[Entity, str] | None:
        root = self._load_quiet(path)
        if root is None:
            return None
        stack = [root]
        while stack:
            entity = stack.pop(0)
            for attribute, value in entity.attributes.items():
                if name in set(_arg_references(value)):
                    return entity, attribute
            if entity.text and entity.tag == "rosparam" and name in set(
                    _arg_references(entity.text)):
                return entity, ""
            stack[0:0] = entity.children
        return None

    def _load_quiet(self, path: str) -> Entity | None:
        from orchestra.launch.convert import load_entity

        try:
            return load_entity(path)
        except OrchestraError:
            return None

    # ---------------------------------------------------------------- files and packages
    def _severity(self, taken: bool) -> tuple[str, str]:
        if taken:
            return ERROR, ""
        return WARNING, " (in a branch these args do not take)"

    def _check_packages(self, entity: Entity, name: str, value: str, taken: bool) -> bool:
        """Report ``$(find pkg)`` of unknown packages in ``value``; False if one is missing."""
        from orchestra.packages import PackageNotFound, find_package

        try:
            bodies = substitution.collect(value) if "$" in value else []
        except OrchestraError:
            return True
        ok = True
        for body in bodies:
            words = body.split()
            if len(words) == 2 and words[0] == "find" and "$" not in words[1]:
                try:
                    find_package(words[1])
                except PackageNotFound:
                    severity, note = self._severity(taken)
                    self._problem(severity, self.sources.locate(entity, name),
                                  f"package '{words[1]}' not found{note}", "missing-package")
                    ok = False
        return ok

    def _check_resources(self, entity: Entity, scope: _StaticScope, taken: bool) -> None:
        packages_ok = True
        for name, value in entity.attributes.items():
            packages_ok &= self._check_packages(entity, name, value, taken)
        if entity.tag in ("node", "test"):
            self._check_executable(entity, scope, taken)
        if not packages_ok:
            return
        file_attributes = {"rosparam": ("file",), "param": ("textfile", "binfile")}
        for name in file_attributes.get(entity.tag, ()):
            if entity.tag == "rosparam" and (entity.get("command") or "load") != "load":
                continue  # dump writes the file; delete reads none
            raw = entity.get(name)
            path = _try_resolve(raw, scope)
            if path and not os.path.isfile(path):
                severity, note = self._severity(taken)
                self._problem(severity, self.sources.locate(entity, name),
                              f"{name} '{path}' does not exist{note}", "missing-file")

    def _check_executable(self, entity: Entity, scope: _StaticScope, taken: bool) -> None:
        """The node's package exists and holds exactly one executable of that name."""
        from orchestra.packages import PackageNotFound, find_executable, find_package

        pkg = _try_resolve(entity.get("pkg"), scope)
        exe = _try_resolve(entity.get("type"), scope)
        if not pkg:
            return
        severity, note = self._severity(taken)
        try:
            find_package(pkg)
        except PackageNotFound:
            self._problem(severity, self.sources.locate(entity, "pkg"),
                          f"<{entity.tag}> package '{pkg}' not found{note}", "missing-node")
            return
        if not exe:
            return
        try:
            find_executable(pkg, exe)
        except OrchestraError as exc:
            self._problem(severity, self.sources.locate(entity, "type"), exc.message + note,
                          "missing-node")

    def _check_node_flags(self, entity: Entity, scope: _StaticScope) -> None:
        if entity.tag != "node":
            return
        respawn = _try_resolve(entity.get("respawn"), scope)
        required = _try_resolve(entity.get("required"), scope)
        if respawn and required and _is_true(respawn) and _is_true(required):
            self._problem(ERROR, self.sources.locate(entity, "required"),
                          "a node cannot be both respawn and required (a required node's "
                          "exit ends the launch, so it is never respawned)",
                          "respawn-required")

    # ---------------------------------------------------------------- includes
    def _resolve_include(self, entity: Entity, scope: _StaticScope, path: str,
                         taken: bool) -> _Include | None:
        raw = entity.get("file")
        where = self.sources.locate(entity, "file")
        if not raw:
            self._problem(ERROR, self.sources.locate(entity), "<include> needs a 'file'",
                          "missing-attribute")
            return None
        target = _try_resolve(raw, scope)
        if target is None:
            return None
        target = os.path.abspath(target)
        if not os.path.isfile(target):
            severity, note = self._severity(taken)
            self._problem(severity, where, f"included file '{target}' does not exist{note}",
                          "missing-file")
            return None
        child_args: dict[str, str] = {}
        if _is_true(entity.get("pass_all_args") or "") is True:
            child_args.update(scope.args)
        for child in entity.children:
            if child.tag == "arg" and child.get("name"):
                value = _try_resolve(child.get("value", child.get("default")), scope)
                if value is not None:
                    child_args[child.get("name")] = value
        self.graph.add_edge(path, target, location=where)
        return _Include(path, target, where, child_args)

    def _report_cycles(self) -> bool:
        found = False
        for cycle in networkx.simple_cycles(self.graph):
            found = True
            first = cycle.index(min(cycle))  # report each cycle once, from a stable start
            cycle = cycle[first:] + cycle[:first]
            where = self.graph.edges[cycle[0], cycle[1 % len(cycle)]]["location"]
            chain = " -> ".join(os.path.basename(p) for p in cycle + [cycle[0]])
            self._problem(ERROR, where, f"include cycle: {chain}", "include-cycle")
        return found

    # ---------------------------------------------------------------- interpreter pass
    def _interpret(self, path: str) -> None:
        """Resolve the tree with the real interpreter (no ``command=`` run, nothing started).

        The collecting interpreter reports an error and carries on with the next element, so
        one run lists every problem the given args reach. An error the static pass already
        reported on the same line is not repeated (the static one has the column and code).
        """
        from orchestra.launch.interpreter import LoadOptions

        interp = _CollectingInterpreter(LoadOptions(args=dict(self.cli_args), no_exec=True))
        try:
            interp.load_file(path)
        except OrchestraError as exc:  # the root itself (already reported as syntax)
            interp.errors.append(exc)
        static_lines = {(p.location.file, p.location.line) for p in self.report.problems
                        if p.code in _ALSO_FOUND_BY_INTERPRETER}
        for exc in interp.errors:
            where = exc.location or Location(path)
            if (where.file, where.line) in static_lines:
                continue
            self._problem(ERROR, self._precise(where, exc.message), exc.message, "launch")
        for entity, message in interp.warned:
            where = self.sources.locate(entity)
            if "unknown <" in message or "unrecognized" in message:
                continue  # unknown tags/attributes: the static pass reports them, located
            self._problem(WARNING, where, message, "launch")
        self._check_plan(interp.plan())

    def _precise(self, where: Location, message: str) -> Location:
        """Add the column to an interpreter error location when the file text shows it."""
        if where.line is None or where.column is not None:
            return where
        lines = self.sources.lines(where.file)
        if 0 < where.line <= len(lines):
            text = lines[where.line - 1]
            marker = message.find("attribute '")
            if marker >= 0:
                attribute = message[marker + 11:].split("'", 1)[0]
                col = text.find(f"{attribute}=")
                if col >= 0:
                    return Location(where.file, where.line, col + 1)
            col = text.find("<")
            if col >= 0:
                return Location(where.file, where.line, col + 1)
        return where

    def _check_plan(self, plan: Any) -> None:
        """What only a resolved plan shows and the interpreter lets through: two ``<test>``s
        (or a test and a node) with the same full name (it rejects duplicate nodes itself)."""
        seen: dict[str, Any] = {}
        for node in (*plan.nodes, *plan.tests):
            if node.full_name in seen:
                first = seen[node.full_name]
                self._problem(ERROR, Location(node.filename or "<launch>", node.line),
                              f"duplicate node name {node.full_name} (first at "
                              f"{first.filename}:{first.line})", "duplicate-node")
            else:
                seen[node.full_name] = node


def _collecting_interpreter_class() -> type:
    from orchestra.launch.interpreter import Interpreter

    class CollectingInterpreter(Interpreter):
        """The real interpreter, except that an error skips one element instead of the run.

        Only two methods change: the per-element dispatch (each child is interpreted on
        its own, and an ``OrchestraError`` is recorded instead of raised) and ``_warn`` (the
        Entity is kept for its location). Every tag rule is the interpreter's own.
        """

        def __init__(self, options: Any):
            super().__init__(options)
            self.errors: list[OrchestraError] = []
            self.warned: list[tuple[Entity, str]] = []

        def _children(self, children: list[Entity], scope: Any, default_machine: Any) -> Any:
            for entity in children:
                try:
                    default_machine = super()._children([entity], scope, default_machine)
                except OrchestraError as exc:
                    self.errors.append(exc)
            return default_machine

        def _warn(self, entity: Entity, message: str) -> None:
            self.warned.append((entity, message))
            self.warnings.append(f"{entity.location}: {message}")

    return CollectingInterpreter


class _CollectingInterpreterProxy:
    """Builds the collecting interpreter class on first use (the interpreter is imported
    lazily so ``orchestra convert`` does not pay for it)."""

    _cls: type | None = None

    def __call__(self, options: Any) -> Any:
        if self._cls is None:
            type(self)._cls = _collecting_interpreter_class()
        return self._cls(options)


_CollectingInterpreter = _CollectingInterpreterProxy()


def _substitution_problem(value: str) -> str | None:
    """Why ``value``'s substitutions can never resolve, or None (unset args/env are fine
    here: they depend on how the file is launched)."""
    if "$" not in value:
        return None
    stripped = value.strip()
    if value.startswith("$(eval ") and value.endswith(")"):
        return evaluate.problem(stripped[7:-1])
    try:
        bodies = substitution.collect(value)
    except OrchestraError as exc:
        return exc.message
    arity = {"find": 1, "env": 1, "anon": 1, "arg": 1, "dirname": 0}
    for body in bodies:
        words = body.split()
        if not words or words[0] not in substitution.COMMANDS:
            command = words[0] if words else ""
            hint = _suggest(command, substitution.COMMANDS) if command else ""
            return (f"unknown substitution $({body}){hint}; valid: "
                    f"{', '.join(substitution.COMMANDS)} (and a whole-value $(eval ...))")
        if words[0] == "eval":
            return "$(eval ...) must be the whole value"
        expected = arity.get(words[0])
        if expected is not None and len(words) - 1 != expected:
            return f"$({words[0]}) takes {expected} argument(s): $({body})"
        if words[0] == "optenv" and len(words) < 2:
            return f"$(optenv) needs a variable name: $({body})"
    return None


def _suggest(name: str, known: Any) -> str:
    close = difflib.get_close_matches(name, list(known), n=1, cutoff=0.75)
    return f" (did you mean '{close[0]}'?)" if close else ""


def check_files(paths: list[str], cli_args: dict[str, str] | None = None) -> Report:
    """Check each top-level file (and what it includes) with the same command-line args."""
    checker = Checker(cli_args)
    for path in paths:
        checker.check(path)
    return checker.report


def check_tree(paths: list[str], cli_args: dict[str, str] | None = None) -> Report:
    """Check a set of files such as a package's launch directory: files that another file of
    the set includes are checked through that include (with the args it passes), not on
    their own, where their required args would look missing."""
    probe = Checker(cli_args)
    for path in paths:
        probe._check_file(os.path.abspath(path), dict(probe.cli_args), top=True)
    included = {target for _, target in probe.graph.edges}
    roots = [path for path in paths if os.path.abspath(path) not in included]
    return check_files(roots or paths, cli_args)
