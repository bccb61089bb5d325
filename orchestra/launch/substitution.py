"""``$(...)`` substitution args, evaluated the way roslaunch evaluates them.

Order matters and is roslaunch's: a value that is exactly ``$(eval EXPR)`` is a Python
expression evaluated in a sandbox; otherwise ``$(dirname)``, ``$(env)``, ``$(optenv)``,
``$(anon)`` and ``$(arg)`` are replaced first (left to right, each replacing every identical
occurrence), and ``$(find pkg)`` last, because the path written after ``$(find pkg)`` may
itself come from an arg. There are no escapes: a ``$`` inside ``$(...)`` is an error.

The ``$(eval)`` sandbox: no double underscore anywhere in the expression, no attribute
starting with ``_``, and only the names roslaunch documents (``arg``, ``env``, ``optenv``,
``find``, ``anon``, ``dirname``, ``true``/``false``, declared args by bare name) plus a few
side-effect-free builtins. ``open``, ``__import__``, ``getattr`` and friends do not exist there.
"""
from __future__ import annotations

import ast
import builtins
import os
import re
from collections.abc import Callable, Mapping
from typing import Any, Protocol

from orchestra.errors import OrchestraError
from orchestra.names import anonymous_name

COMMANDS = ("find", "env", "optenv", "dirname", "anon", "arg")


class SubstitutionError(OrchestraError):
    """A ``$(...)`` that cannot be evaluated (unknown command, unset variable, bad eval)."""


class ArgNotSet(SubstitutionError):
    """``$(arg name)`` for an arg that has no value here; ``.name`` is the arg."""

    def __init__(self, name: str):
        super().__init__(f"arg '{name}' is not set (declare it with a value or default, "
                         "or pass it as name:=value)")
        self.name = name


class Scope(Protocol):
    """What substitution needs from the loader scope."""

    args: Mapping[str, str]
    filename: str | None


def _find_package(name: str) -> str:
    # imported lazily: the package index is only needed by files that use $(find)
    from orchestra.packages import find_package
    return find_package(name)


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
                raise SubstitutionError(f"'$' cannot appear inside a substitution arg [{text}]")
        elif ch == "(":
            if state == 1:
                state = 2
            elif state != 0:
                raise SubstitutionError(f"invalid '(' inside a substitution arg [{text}]")
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
    if len(pkg_args) != 1:
        raise SubstitutionError(f"$(find pkg) takes exactly one argument [$({body})]")
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


def _first_pass(resolved: str, body: str, words: list[str], scope: Scope) -> str:
    command, args = words[0], words[1:]
    token = f"$({body})"
    if command == "env":
        if len(args) != 1:
            raise SubstitutionError(f"$(env var) takes exactly one argument [{token}]")
        return resolved.replace(token, _env(args[0]))
    if command == "optenv":
        if not args:
            raise SubstitutionError(f"$(optenv var) needs a variable name [{token}]")
        value = os.environ.get(args[0])
        if value is None:
            value = " ".join(args[1:])
        return resolved.replace(token, value)
    if command == "anon":
        if len(args) != 1:
            raise SubstitutionError(f"$(anon name) takes exactly one name [{token}]")
        return resolved.replace(token, anonymous_name(args[0]))
    if command == "arg":
        if len(args) != 1:
            raise SubstitutionError(f"$(arg name) takes exactly one name [{token}]")
        if args[0] not in scope.args:
            raise ArgNotSet(args[0])
        return resolved.replace(token, scope.args[args[0]])
    if command == "dirname":
        return resolved.replace(token, _dirname(scope))
    return resolved


def resolve(text: str | None, scope: Scope) -> str | None:
    """``text`` with every substitution arg evaluated; ``None`` stays ``None``."""
    if not text or "$" not in text:
        return text
    if text.startswith("$(eval ") and text.endswith(")"):
        return str(evaluate(text[7:-1], scope))
    bodies = collect(text)
    parsed = []
    for body in bodies:
        words = [w for w in body.split(" ") if w]
        if not words or words[0] not in COMMANDS:
            raise SubstitutionError(f"unknown substitution command [$({body})]; valid commands "
                                    f"are {', '.join(COMMANDS)} (and a whole-value $(eval ...))")
        parsed.append((body, words))
    resolved = text
    for body, words in parsed:
        resolved = _first_pass(resolved, body, words, scope)
    if "$" in resolved:
        for body in collect(resolved):
            words = [w for w in body.split(" ") if w]
            if not words or words[0] not in COMMANDS:
                raise SubstitutionError(f"unknown substitution command [$({body})]")
            if words[0] == "find":
                resolved = _find(resolved, body, words[1:])
    return resolved


# ---------------------------------------------------------------------------- $(eval) sandbox

_SAFE_BUILTINS: dict[str, Any] = {
    name: getattr(builtins, name)
    for name in ("abs", "all", "any", "bool", "dict", "divmod", "enumerate", "filter", "float",
                 "int", "len", "list", "map", "max", "min", "pow", "range", "reversed",
                 "round", "set", "sorted", "str", "sum", "tuple", "zip")
}
_FORBIDDEN_ATTRS = {"format", "format_map", "mro"}
_MAX_EXPONENT = 64


def _check_expression(expr: str) -> ast.Expression:
    if "__" in expr:
        raise SubstitutionError("$(eval ...) may not contain double underscores")
    try:
        tree = ast.parse(expr.strip(), mode="eval")
    except SyntaxError as exc:
        raise SubstitutionError(f"$(eval {expr}): invalid expression: {exc.msg}") from None
    for node in ast.walk(tree):
        if isinstance(node, ast.Attribute) and (node.attr.startswith("_")
                                                or node.attr in _FORBIDDEN_ATTRS):
            raise SubstitutionError(f"$(eval ...) may not use the attribute '{node.attr}'")
        if isinstance(node, (ast.Lambda, ast.NamedExpr)):
            raise SubstitutionError("$(eval ...) may not define functions or assign")
        if isinstance(node, ast.BinOp) and isinstance(node.op, ast.Pow):
            exponent = node.right
            if not (isinstance(exponent, ast.Constant) and isinstance(exponent.value, (int, float))
                    and abs(exponent.value) <= _MAX_EXPONENT):
                raise SubstitutionError("$(eval ...) exponents must be literal numbers up to "
                                        f"{_MAX_EXPONENT} (no runaway computations)")
    return tree


class _Names(dict):
    """The eval namespace: functions first, then declared args converted like roslaunch."""

    def __init__(self, functions: dict[str, Callable[..., Any]], args: Mapping[str, str]):
        super().__init__()
        self._functions = functions
        self._args = args

    def __missing__(self, key: str) -> Any:
        if key in self._functions:
            return self._functions[key]
        if key in self._args:
            from orchestra.launch.values import convert_value
            return convert_value(self._args[key], "auto")
        raise KeyError(key)


def evaluate(expr: str, scope: Scope) -> Any:
    """Evaluate a ``$(eval)`` expression in the sandbox."""
    tree = _check_expression(expr)

    def arg(name: str) -> Any:
        # like a bare name, arg('x') is typed: 'false' is False, '3' is 3
        if name not in scope.args:
            raise ArgNotSet(name)
        from orchestra.launch.values import convert_value
        return convert_value(scope.args[name], "auto")

    def optenv(name: str, default: str = "") -> str:
        return os.environ.get(name, default)

    functions: dict[str, Callable[..., Any] | bool] = {
        "arg": arg, "env": _env, "optenv": optenv, "find": _find_package,
        "anon": anonymous_name, "dirname": lambda: _dirname(scope),
        "true": True, "false": False, "True": True, "False": False,
    }
    names = _Names(functions, scope.args)
    try:
        code = compile(tree, "<eval>", "eval")
        return eval(code, {"__builtins__": _SAFE_BUILTINS}, names)  # noqa: S307 (sandboxed)
    except OrchestraError:
        raise
    except NameError as exc:
        raise SubstitutionError(f"$(eval {expr}): {exc} (only args, arg(), env(), optenv(), "
                                "find(), anon(), dirname() and basic builtins exist)") from None
    except Exception as exc:  # any runtime error of the user's expression
        raise SubstitutionError(f"$(eval {expr}): {type(exc).__name__}: {exc}") from None
