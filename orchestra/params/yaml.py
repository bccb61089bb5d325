"""rosparam's YAML rules: what a YAML document means as parameter values.

Loading is always *safe* (no arbitrary Python objects). On top of YAML 1.1 (PyYAML's rules,
which rosparam uses: ``yes``/``no`` are booleans, ``1e5`` without a dot is a string), rosparam
adds angle tags: ``!degrees 90`` / ``deg(90)`` become radians, ``!radians pi/2`` / ``rad(pi/2)``
evaluate a small arithmetic expression over ``pi``; ``!!binary`` is raw bytes. The expression
evaluator below only knows numbers, ``pi`` and arithmetic, unlike rosparam's ``eval``.
"""
from __future__ import annotations

import ast
import math
import operator
import re
from collections.abc import Callable
from typing import Any

import yaml

from orchestra.errors import Location, OrchestraError
from orchestra.names import ns_join


class RosparamYamlError(OrchestraError):
    """A YAML document rosparam could not load."""


_BINOPS: dict[type[ast.operator], Callable[[float, float], float]] = {
    ast.Add: operator.add, ast.Sub: operator.sub, ast.Mult: operator.mul,
    ast.Div: operator.truediv, ast.Pow: operator.pow, ast.Mod: operator.mod,
    ast.FloorDiv: operator.floordiv}
_UNARY: dict[type[ast.unaryop], Callable[[float], float]] = {ast.USub: operator.neg, ast.UAdd: operator.pos}


def _arith(node: ast.AST) -> float:
    if isinstance(node, ast.Expression):
        return _arith(node.body)
    if isinstance(node, ast.Constant) and isinstance(node.value, (int, float)) \
            and not isinstance(node.value, bool):
        return node.value
    if isinstance(node, ast.Name) and node.id == "pi":
        return math.pi
    if isinstance(node, ast.BinOp) and type(node.op) in _BINOPS:
        return _BINOPS[type(node.op)](_arith(node.left), _arith(node.right))
    if isinstance(node, ast.UnaryOp) and type(node.op) in _UNARY:
        return _UNARY[type(node.op)](_arith(node.operand))
    raise ValueError("only numbers, pi and + - * / ** % are allowed")


def angle_expression(text: str) -> float:
    """Evaluate an angle expression such as ``pi/2`` or ``-1.5*pi`` (no names but ``pi``)."""
    return float(_arith(ast.parse(text.strip(), mode="eval")))


def _unwrap(value: str, prefix: str) -> str:
    value = value.strip()
    if value.startswith(prefix + "(") and value.endswith(")"):
        return value[len(prefix) + 1:-1]
    return value


def _construct_radians(loader: yaml.SafeLoader, node: yaml.ScalarNode) -> float:
    text = _unwrap(loader.construct_scalar(node), "rad")
    try:
        return angle_expression(text)
    except (ValueError, SyntaxError, ZeroDivisionError, TypeError) as exc:
        raise yaml.constructor.ConstructorError(
            None, None, f"invalid radian expression {text!r}: {exc}", node.start_mark) from None


def _construct_degrees(loader: yaml.SafeLoader, node: yaml.ScalarNode) -> float:
    text = _unwrap(loader.construct_scalar(node), "deg")
    try:
        return float(text) * math.pi / 180.0
    except ValueError:
        raise yaml.constructor.ConstructorError(
            None, None, f"invalid degree value {text!r}", node.start_mark) from None


class RosparamLoader(getattr(yaml, "CSafeLoader", yaml.SafeLoader)):  # type: ignore[misc]
    """PyYAML's safe loader (libyaml-backed when available: same results, much faster) plus
    rosparam's angle tags; a subclass, so the global loaders stay untouched."""


RosparamLoader.add_constructor("!radians", _construct_radians)
RosparamLoader.add_constructor("!degrees", _construct_degrees)
RosparamLoader.add_implicit_resolver("!radians", re.compile(r"^rad\([^)]*\)$"), ["r"])
RosparamLoader.add_implicit_resolver("!degrees", re.compile(r"^deg\([^)]*\)$"), ["d"])


def load_rosparam_yaml(text: str, filename: str = "<yaml>") -> Any:
    """The value rosparam loads from ``text``; an empty document is ``{}``.

    Errors become ``RosparamYamlError`` located at ``filename:line`` of the problem.
    """
    data = load_yaml_value(text, filename)
    return {} if data is None else data


def load_yaml_value(text: str, filename: str = "<yaml>") -> Any:
    """Like ``load_rosparam_yaml`` but an empty document is ``None`` (``type="yaml"`` params)."""
    try:
        data = yaml.load(text, Loader=RosparamLoader)  # noqa: S506 (safe subclass)
    except yaml.MarkedYAMLError as exc:
        mark = exc.problem_mark or exc.context_mark
        line = mark.line + 1 if mark is not None else None
        col = mark.column + 1 if mark is not None else None
        raise RosparamYamlError(f"invalid YAML: {exc.problem or exc}",
                                Location(filename, line, col)) from None
    except yaml.YAMLError as exc:
        raise RosparamYamlError(f"invalid YAML: {exc}", Location(filename)) from None
    return data


def flatten(name: str, value: Any) -> list[tuple[str, Any]]:
    """Unroll dictionaries into leaf parameters the way roslaunch stores ``<rosparam>``.

    ``flatten('/ns', {'a': {'b': 1}, 'c': 2})`` -> ``[('/ns/a/b', 1), ('/ns/c', 2)]``. An empty
    dictionary contributes nothing; a global key inside a dictionary escapes the namespace.
    """
    out: list[tuple[str, Any]] = []
    stack = [(name, value)]
    while stack:
        key, val = stack.pop()
        if isinstance(val, dict):
            for sub in reversed(list(val.items())):
                stack.append((ns_join(key, str(sub[0])), sub[1]))
        else:
            out.append((key, val))
    return out


__all__ = ["RosparamLoader", "RosparamYamlError", "angle_expression", "flatten",
           "load_rosparam_yaml", "load_yaml_value"]
