"""``$(...)`` substitution args, evaluated the way roslaunch evaluates them.

Order matters and is roslaunch's: a value that is exactly ``$(eval EXPR)`` is a Python
expression evaluated in a sandbox; otherwise ``$(dirname)``, ``$(env)``, ``$(optenv)``,
``$(anon)`` and ``$(arg)`` are replaced first (left to right, each replacing every identical
occurrence), and ``$(find pkg)`` last, because the path written after ``$(find pkg)`` may
itself come from an arg. There are no escapes: a ``$`` inside ``$(...)`` is an error.

``$(eval)`` is never given to Python's ``eval``: ``orchestra.launch.evaluate`` interprets a
whitelisted expression grammar with bounded sizes and work; this module supplies the launch
functions (``arg``, ``env``, ``optenv``, ``find``, ``anon``, ``dirname``) it calls.
"""
from __future__ import annotations

import os
import re
from collections.abc import Callable, Mapping
from typing import Any, Protocol

from orchestra.errors import OrchestraError, clip
from orchestra.names import anonymous_name

COMMANDS = ("find", "env", "optenv", "dirname", "anon", "arg")
# how many words each command takes after its name: (fewest, most; None = no limit).
# roslaunch ignores words after $(dirname); $(optenv VAR default words...) joins them.
ARITY: dict[str, tuple[int, int | None]] = {
    "find": (1, 1), "env": (1, 1), "optenv": (1, None), "dirname": (0, None), "anon": (1, 1),
    "arg": (1, 1),
}


class SubstitutionError(OrchestraError):
    """A ``$(...)`` that cannot be evaluated (unknown command, unset variable, bad eval)."""


class ArgNotSet(SubstitutionError):
    """``$(arg name)`` for an arg that has no value here; ``.name`` is the arg."""

    def __init__(self, name: str):
        super().__init__(f"arg '{name}' is not set (declare it with a value or default, "
                         "or pass it as name:=value)")
        self.name = name


class Scope(Protocol):
    """What substitution needs from the loader scope (read only)."""

    @property
    def args(self) -> Mapping[str, str]: ...

    @property
    def filename(self) -> str | None: ...


def _find_package(name: str) -> str:
    # imported lazily: the package index is only needed by files that use $(find). (A
    # plain dotted import: ``from package import name`` runs importlib's Python fromlist
    # handling on every call, a fifth of a $(find).)
    import orchestra.packages.index
    return orchestra.packages.index.find_package(name)


_SIMPLE_GROUP = re.compile(r"\$\(([^$()]+)\)")


def collect(text: str) -> list[str]:
    """The bodies of the ``$(...)`` groups in ``text``, in order (roslaunch's scanner)."""
    if "$(" not in text:
        return []
    # fast path for the usual text; anything unusual goes through the exact scanner below
    simple = _SIMPLE_GROUP.findall(text)
    if "$(" not in _SIMPLE_GROUP.sub("", text):
        return simple
    return _scan(text)


def _scan(text: str) -> list[str]:
    found: list[str] = []
    buf: list[str] = []
    state = 0  # 0 outside, 1 after '$', 2 after '$(', 3 inside
    for ch in text:
        if ch == "$":
            if state == 0:
                state = 1
            elif state != 1:
                raise SubstitutionError(f"'$' cannot appear inside a substitution arg [{clip(text)}]")
        elif ch == "(":
            if state == 1:
                state = 2
            elif state != 0:
                raise SubstitutionError(f"invalid '(' inside a substitution arg [{clip(text)}]")
        elif ch == ")":
            if state == 3:
                found.append("".join(buf))
                buf.clear()
            state = 0
        elif state == 1:
            state = 0
        elif state == 2:
            state = 3
        if state == 3:
            buf.append(ch)
    return found


def words(body: str) -> list[str]:
    """The words of a ``$(...)`` body: split at spaces, as roslaunch does (not at tabs)."""
    return [w for w in body.split(" ") if w]


def eval_expression(text: str) -> str | None:
    """The expression of a value that is exactly ``$(eval EXPR)``, else None."""
    if text.startswith("$(eval ") and text.endswith(")"):
        return text[7:-1]
    return None


def body_problem(body: str) -> str | None:
    """Why the ``$(...)`` group ``body`` can never be evaluated (unknown command, wrong
    number of words), or None."""
    parts = words(body)
    if not parts or parts[0] not in COMMANDS:
        return (f"unknown substitution command [$({body})]; valid commands are "
                f"{', '.join(COMMANDS)} (and a whole-value $(eval ...))")
    fewest, most = ARITY[parts[0]]
    given = len(parts) - 1
    if given < fewest or (most is not None and given > most):
        wanted = str(fewest) if fewest == most else f"at least {fewest}"
        return f"$({parts[0]}) takes {wanted} argument(s) [$({body})]"
    return None


def _env(name: str) -> str:
    try:
        return os.environ[name]
    except KeyError:
        raise SubstitutionError(f"environment variable '{name}' is not set") from None


def _dirname(scope: Scope) -> str:
    if not scope.filename:
        raise SubstitutionError("$(dirname) needs a file: none is being read here")
    return os.path.abspath(os.path.dirname(scope.filename))


def _find(resolved: str, body: str, pkg_args: list[str]) -> str:
    """Replace the first ``$(find pkg)`` and the path word after it, like roslaunch."""
    token = f"$({body})"
    idx = resolved.find(token)
    before, after = resolved[:idx], resolved[idx + len(token):]
    space = after.find(" ")
    path, rest = (after, "") if space < 0 else (after[:space], after[space:])
    path = path.replace("\\", "/")
    if path.startswith("/"):
        path = path[1:]
    pkg_dir = _find_package(pkg_args[0])
    if path:
        return before + os.path.join(pkg_dir, path) + rest
    return before + pkg_dir + rest


def _first_pass(resolved: str, token: str, words: list[str], scope: Scope) -> str:
    command, args = words[0], words[1:]
    if command == "env":
        return resolved.replace(token, _env(args[0]))
    if command == "optenv":
        value = os.environ.get(args[0])
        if value is None:
            value = " ".join(args[1:])
        return resolved.replace(token, value)
    if command == "anon":
        return resolved.replace(token, anonymous_name(args[0]))
    if command == "arg":
        if args[0] not in scope.args:
            raise ArgNotSet(args[0])
        return resolved.replace(token, scope.args[args[0]])
    if command == "dirname":
        return resolved.replace(token, _dirname(scope))
    return resolved


# A text's groups, checked: ``(token, words)`` per group, or None for a whole-value
# ``$(eval)``. The same few texts (``$(arg x)``, ``$(find pkg)/...``) recur on every element
# of a file, so each text is scanned once; only texts that parse are kept, and the table is
# emptied when it grows past _PARSED_LIMIT distinct texts.
_PARSED: dict[str, list[tuple[str, list[str]]] | None] = {}
_PARSED_LIMIT = 4096


def _parse(text: str) -> list[tuple[str, list[str]]] | None:
    found = _PARSED.get(text, False)
    if found is not False:
        return found  # type: ignore[return-value]
    if eval_expression(text) is not None:
        parsed = None
    else:
        parsed = []
        for body in collect(text):
            problem = body_problem(body)
            if problem is not None:
                raise SubstitutionError(problem)
            parsed.append((f"$({body})", words(body)))
    if len(_PARSED) >= _PARSED_LIMIT:
        _PARSED.clear()
    _PARSED[text] = parsed
    return parsed


def resolve(text: str | None, scope: Scope) -> str | None:
    """``text`` with every substitution arg evaluated; ``None`` stays ``None``."""
    if not text or "$" not in text:
        return text
    parsed = _parse(text)
    if parsed is None:
        return _eval(text[7:-1], scope)
    resolved = text
    for token, parts in parsed:
        resolved = _first_pass(resolved, token, parts, scope)
    if "$" in resolved:
        for body, pkg_args in _finds(resolved):
            resolved = _find(resolved, body, pkg_args)
    return resolved


# The second pass's groups of a text (what the first pass left), checked, as _PARSED keeps
# the first pass's: ``$(find pkg)/...`` texts are the same on many elements.
_FINDS: dict[str, list[tuple[str, list[str]]]] = {}


def _finds(resolved: str) -> list[tuple[str, list[str]]]:
    """The ``$(find)`` groups of ``resolved`` as (body, its words after ``find``), in order.

    $(find) goes last; what the first pass left (from arg values) is only checked for
    unknown commands, as roslaunch does."""
    found = _FINDS.get(resolved)
    if found is not None:
        return found
    found = []
    for body in collect(resolved):
        parts = words(body)
        problem = body_problem(body)
        if problem is not None and (not parts or parts[0] not in COMMANDS
                                    or parts[0] == "find"):
            raise SubstitutionError(problem)
        if parts[0] == "find":
            found.append((body, parts[1:]))
    if len(_FINDS) >= _PARSED_LIMIT:
        _FINDS.clear()
    _FINDS[resolved] = found
    return found


# ----------------------------------------------------------------------------- $(eval)


def _convert_arg(text: str) -> Any:
    # imported lazily: values pulls in the YAML loader, which plain substitution never needs
    from orchestra.launch.values import convert_value
    return convert_value(text, "auto")


def _eval(expr: str, scope: Scope) -> str:
    """``$(eval EXPR)`` through the safe evaluator, with the launch functions of ``scope``."""
    # imported here: the evaluator's module (policy, grammar) is a millisecond of every
    # launch's start-up that only files with $(eval) need
    from orchestra.launch.evaluate import EvalError, evaluate

    def arg(name: str) -> Any:
        # like a bare name, arg('x') is typed: 'false' is False, '3' is 3
        if not isinstance(name, str) or name not in scope.args:
            raise ArgNotSet(str(name))
        return _convert_arg(scope.args[name])

    def optenv(name: str, default: str = "") -> str:
        return os.environ.get(name, default)

    launch: dict[str, Callable[..., Any]] = {
        "arg": arg, "env": _env, "optenv": optenv, "find": _find_package,
        "anon": anonymous_name, "dirname": lambda: _dirname(scope),
    }
    try:
        return evaluate(expr, scope.args, launch, _convert_arg)
    except EvalError as exc:
        raise SubstitutionError(exc.message) from None
