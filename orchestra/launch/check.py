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
from orchestra.launch import evaluate, frontends, rules, substitution
from orchestra.launch.context import Scope
from orchestra.launch.entity import Entity
from orchestra.launch.interpreter import Interpreter, LoadOptions
from orchestra.launch.plan import Machine
from orchestra.launch.rules import LaunchError

log = logging.getLogger(__name__)

ERROR = "error"
WARNING = "warning"

# Static findings the interpreter also raises when it reaches the element: an interpreter
# error about an element that already has one of these is the same problem, already reported.
_ALSO_FOUND_BY_INTERPRETER = frozenset({
    "syntax", "missing-package", "missing-file", "include-cycle", "respawn-required",
    rules.IF_UNLESS, "bad-substitution", rules.MISSING_ATTRIBUTE, "undeclared-arg",
    rules.BAD_VALUE, rules.FORBIDDEN_ATTRIBUTE,
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
    plans: list[Any] = field(default_factory=list)    # resolved plans (``--check-machines``)

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


def _branch_taken(entity: Entity, scope: _StaticScope) -> bool | None:
    """False when the element's if/unless resolves to "not taken"; None when unknown."""
    for name, want in (("if", True), ("unless", False)):
        raw = entity.get(name)
        if raw is None:
            continue
        value = _try_resolve(raw, scope)
        if value is None:
            return None
        truth = rules.truth(entity.tag, name, value)
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
    expression = substitution.eval_expression(value)
    if expression is not None:
        yield from _eval_references(expression)
        return
    try:
        bodies = substitution.collect(value)
    except OrchestraError:
        return
    for body in bodies:
        words = substitution.words(body)
        if len(words) == 2 and words[0] == "arg":
            yield words[1]


def _eval_references(expr: str) -> Iterator[str]:
    tree = evaluate.parse_tree(expr)
    if tree is None:
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
        self.cli_args = dict(cli_args or {})
        self.report = Report()
        self.graph = networkx.DiGraph()
        self._checked: set[str] = set()
        # elements (file, line of their start tag) the static pass already found wrong in a
        # way the interpreter would reject too: its error there is the same problem
        self._found_elements: set[tuple[str, int | None]] = set()

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

    def _report(self, severity: str, entity: Entity, message: str, code: str,
                attribute: str | None = None) -> None:
        """A problem with ``entity`` (at ``attribute`` when given), located exactly."""
        self._problem(severity, entity.where(attribute), message, code)
        if code in _ALSO_FOUND_BY_INTERPRETER:
            self._found_elements.add((entity.location.file, entity.location.line))

    def _load(self, path: str) -> Entity | None:
        try:
            return frontends.parse_file(path)
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
            self._report(ERROR, root, f"the root element must be <launch>, not <{root.tag}>",
                         rules.UNKNOWN_TAG)
            return True
        scope = _StaticScope(dict(passed_args), path)
        declared: dict[str, Entity] = {}
        used: set[str] = set()
        passes_all = False
        includes: list[_Include] = []
        for entity, parent, taken in self._walk(root, None, scope, True):
            rule = self._check_tag(entity, parent)
            if rule is not None:
                self._check_attributes(entity, rule, scope, taken)
            self._check_substitutions(entity, taken)
            for value in entity.attributes.values():
                used.update(_arg_references(value))
            if entity.text and entity.tag == "rosparam":
                used.update(_arg_references(entity.text))
            if entity.tag == "arg" and (parent is None or parent.tag != "include"):
                name = entity.get("name")
                if name:
                    declared.setdefault(name, entity)
            if entity.tag == "include" and _passes_all_args(entity, scope):
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
    def _check_tag(self, entity: Entity, parent: Entity | None) -> rules.TagRule | None:
        """Whether ``entity`` may stand where it is; the rule it is read by, if any."""
        if parent is None:
            return rules.rule(entity.tag)
        parent_rule = rules.TAGS.get(parent.tag)
        read_as = parent_rule.child_tag(entity.tag) if parent_rule is not None else None
        if read_as is None:
            if entity.tag in rules.TAGS:
                message = f"<{entity.tag}> is not allowed inside <{parent.tag}>"
            else:
                message = f"unknown tag <{entity.tag}>" + _suggest(entity.tag, rules.TAGS)
            self._report(ERROR, entity, message + " (roslaunch ignores it)", rules.UNKNOWN_TAG)
            return None
        return rules.TAGS[read_as]

    def _check_attributes(self, entity: Entity, rule: rules.TagRule, scope: _StaticScope,
                          taken: bool) -> None:
        """The rule table's attribute rules: unknown, both if and unless, missing required,
        forbidden, and values of the wrong kind (when they resolve without running
        anything)."""
        for name in entity.attributes:
            if name not in rule.allowed:
                self._report(WARNING, entity, f"unknown attribute '{name}' of <{entity.tag}>"
                             + _suggest(name, rule.allowed) + " (roslaunch ignores it)",
                             rules.UNKNOWN_ATTRIBUTE, name)
        if entity.has("if") and entity.has("unless") and rule.attributes["if"].kind is rules.CONDITION:
            self._report(ERROR, entity, f"<{entity.tag}> has both 'if' and 'unless'",
                         rules.IF_UNLESS, "unless")
        severity, note = self._severity(taken)
        missing = [a for a in rule.required if not entity.has(a)]
        if missing:
            names = ", ".join(f"'{a}'" for a in missing)
            self._report(severity, entity,
                         f"<{entity.tag}> is missing required attribute(s) {names}{note}",
                         rules.MISSING_ATTRIBUTE)
        for name in rule.forbidden:
            if entity.has(name):
                self._report(severity, entity, f"<{entity.tag}> cannot have attribute "
                             f"'{name}'{note}", rules.FORBIDDEN_ATTRIBUTE, name)
        for name, value in entity.attributes.items():
            attr = rule.attributes.get(name)
            if attr is None or attr.kind is rules.STRING:
                continue
            resolved = _try_resolve(value, scope)
            if resolved is None:
                continue
            try:
                rules.parse(rule.tag, name, resolved)
            except ValueError as exc:
                self._report(severity, entity, f"<{entity.tag}> attribute '{name}': "
                             f"{exc}{note}", rules.BAD_VALUE, name)

    def _check_substitutions(self, entity: Entity, taken: bool) -> None:
        """``$(...)`` that can never resolve: unknown command, wrong word count, bad eval."""
        values = list(entity.attributes.items())
        if entity.tag == "rosparam" and entity.text and rules.truth(
                "rosparam", "subst_value", entity.get("subst_value") or "") is True:
            values.append(("subst_value", entity.text))
        for name, value in values:
            problem = _substitution_problem(value)
            if problem:
                severity, note = self._severity(taken)
                self._report(severity, entity, f"attribute '{name}': {problem}{note}",
                             "bad-substitution", name)

    # ---------------------------------------------------------------- args
    def _check_args(self, path: str, declared: dict[str, Entity], used: set[str],
                    passes_all: bool, passed: set[str], top: bool) -> None:
        # args handed in (command line for the top file, pass_all_args or <arg> children of
        # the include for others) are visible to $(arg) even when the file does not declare
        # them, as in roslaunch
        known = set(declared) | passed
        for name in sorted(used - known):
            use = self._first_use(path, name)
            message = (f"arg '{name}' is used but never declared in this file"
                       + (" (nor given on the command line)" if top else ""))
            if use is None:
                self._problem(ERROR, Location(path), message, "undeclared-arg")
            else:
                self._report(ERROR, use[0], message, "undeclared-arg", use[1] or None)
        if passes_all:
            return  # pass_all_args hands every arg on: none is unused here
        for name, entity in declared.items():
            if name not in used:
                self._report(WARNING, entity, f"arg '{name}' is declared but never used",
                             "unused-arg", "name")

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
        try:
            return frontends.parse_file(path)
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
            words = substitution.words(body)
            if len(words) == 2 and words[0] == "find" and "$" not in words[1]:
                try:
                    find_package(words[1])
                except PackageNotFound:
                    severity, note = self._severity(taken)
                    self._report(severity, entity, f"package '{words[1]}' not found{note}",
                                 "missing-package", name)
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
                self._report(severity, entity, f"{name} '{path}' does not exist{note}",
                             "missing-file", name)

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
            self._report(severity, entity, f"<{entity.tag}> package '{pkg}' not found{note}",
                         "missing-node", "pkg")
            return
        if not exe:
            return
        try:
            find_executable(pkg, exe)
        except OrchestraError as exc:
            self._report(severity, entity, exc.message + note, "missing-node", "type")

    def _check_node_flags(self, entity: Entity, scope: _StaticScope) -> None:
        if entity.tag != "node":
            return
        respawn = _try_resolve(entity.get("respawn"), scope)
        required = _try_resolve(entity.get("required"), scope)
        if (respawn and required and rules.truth("node", "respawn", respawn)
                and rules.truth("node", "required", required)):
            self._report(ERROR, entity, "a node cannot be both respawn and required (a "
                         "required node's exit ends the launch, so it is never respawned)",
                         "respawn-required", "required")

    # ---------------------------------------------------------------- includes
    def _resolve_include(self, entity: Entity, scope: _StaticScope, path: str,
                         taken: bool) -> _Include | None:
        raw = entity.get("file")
        where = entity.where("file")
        if not raw:
            if entity.has("file"):
                self._report(ERROR, entity, "<include> needs a 'file'", rules.MISSING_ATTRIBUTE)
            return None
        target = _try_resolve(raw, scope)
        if target is None:
            return None
        target = os.path.abspath(target)
        if not os.path.isfile(target):
            severity, note = self._severity(taken)
            self._report(severity, entity, f"included file '{target}' does not exist{note}",
                         "missing-file", "file")
            return None
        child_args: dict[str, str] = {}
        if _passes_all_args(entity, scope):
            child_args.update(scope.args)
        for child in entity.children:
            name = child.get("name")
            if child.tag == "arg" and name:
                value = _try_resolve(child.get("value", child.get("default")), scope)
                if value is not None:
                    child_args[name] = value
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
        interp = _CollectingInterpreter(LoadOptions(args=dict(self.cli_args), no_exec=True))
        try:
            interp.load_file(path)
        except OrchestraError as failure:  # the root itself (already reported as syntax)
            interp.errors.append(failure)
        for error in interp.errors:
            where = error.location or Location(path)
            if (where.file, where.line) in self._found_elements:
                continue
            if isinstance(error, LaunchError):
                self._problem(ERROR, error.exact or where, error.message, error.code)
            else:
                self._problem(ERROR, where, error.message, rules.INVALID)
        for finding in interp.findings:
            if finding.code in (rules.UNKNOWN_TAG, rules.UNKNOWN_ATTRIBUTE):
                continue  # the static pass reports them in every branch
            self._problem(WARNING, finding.exact or finding.location, finding.message,
                          finding.code)
        self._check_plan(interp.plan())

    def _check_plan(self, plan: Any) -> None:
        """What only a resolved plan shows and the interpreter lets through: two ``<test>``s
        (or a test and a node) with the same full name (it rejects duplicate nodes itself)."""
        self.report.plans.append(plan)
        seen: dict[str, Any] = {}
        for node in (*plan.nodes, *plan.tests):
            if node.full_name in seen:
                first = seen[node.full_name]
                self._problem(ERROR, Location(node.filename or "<launch>", node.line),
                              f"duplicate node name {node.full_name} (first at "
                              f"{first.filename}:{first.line})", "duplicate-node")
            else:
                seen[node.full_name] = node


@dataclass(frozen=True)
class Finding:
    """A non-fatal problem the interpreter met (it goes on, as roslaunch does). Here, not
    with the tag rules: only ``orchestra check`` keeps them as values, and every launch
    process would otherwise build the class (~5 M instructions)."""

    location: Location
    message: str
    code: str
    tag: str | None = None
    attribute: str | None = None
    exact: Location | None = field(default=None, compare=False)


class _CollectingInterpreter(Interpreter):
    """The real interpreter, except that an error skips one element instead of the run.

    Only two methods change: the per-element dispatch (each child is interpreted on its own,
    and an ``OrchestraError`` is recorded instead of raised) and ``_warn`` (the finding is
    kept as a value). Every tag rule is the interpreter's own.
    """

    def __init__(self, options: LoadOptions):
        super().__init__(options)
        self.errors: list[OrchestraError] = []
        self.findings: list[Finding] = []

    def _children(self, children: list[Entity], scope: Scope,
                  default_machine: Machine | None) -> Machine | None:
        for entity in children:
            try:
                default_machine = super()._children([entity], scope, default_machine)
            except OrchestraError as exc:
                self.errors.append(exc)
        return default_machine

    def _warn(self, entity: Entity, message: str, code: str = rules.INVALID,
              attribute: str | None = None) -> None:
        self.findings.append(Finding(entity.location, message, code, entity.tag,
                                           attribute, entity.where(attribute)))
        self.warnings.append(f"{entity.location}: {message}")


def _substitution_problem(value: str) -> str | None:
    """Why ``value``'s substitutions can never resolve, or None (unset args/env are fine
    here: they depend on how the file is launched)."""
    if "$" not in value:
        return None
    expression = substitution.eval_expression(value)
    if expression is not None:
        return evaluate.problem(expression)
    try:
        bodies = substitution.collect(value)
    except OrchestraError as exc:
        return exc.message
    for body in bodies:
        words = substitution.words(body)
        if words and words[0] == "eval":
            return "$(eval ...) must be the whole value"
        problem = substitution.body_problem(body)
        if problem is not None:
            command = words[0] if words else ""
            if command not in substitution.COMMANDS and command:
                problem += _suggest(command, substitution.COMMANDS)
            return problem
    return None


def _passes_all_args(entity: Entity, scope: _StaticScope) -> bool:
    value = _try_resolve(entity.get("pass_all_args"), scope)
    return value is not None and rules.truth("include", "pass_all_args", value) is True


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
