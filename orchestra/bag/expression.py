"""The safe evaluator of ``bag filter`` expressions.

rosbag filter runs its EXPR through Python's ``eval``: any code. Here the expression is
parsed with ``ast`` and only a whitelist is evaluated: literals, the names given (``topic``,
``m``, ``t``), attribute reads (never a name starting with ``_``), subscripts, arithmetic,
comparisons, ``and``/``or``/``not``, ``x if c else y``, a few pure built-ins and the
read-only methods of strings and times. Anything else is refused when the expression is
compiled, before any message is read.
"""
from __future__ import annotations

import ast
import operator
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

MAX_LENGTH = 2000

_BINOPS: dict[type, Callable[[Any, Any], Any]] = {
    ast.Add: operator.add, ast.Sub: operator.sub, ast.Mult: operator.mul,
    ast.Div: operator.truediv, ast.FloorDiv: operator.floordiv, ast.Mod: operator.mod,
}
_UNARY: dict[type, Callable[[Any], Any]] = {
    ast.USub: operator.neg, ast.UAdd: operator.pos, ast.Not: operator.not_,
}
_COMPARE: dict[type, Callable[[Any, Any], bool]] = {
    ast.Eq: operator.eq, ast.NotEq: operator.ne, ast.Lt: operator.lt, ast.LtE: operator.le,
    ast.Gt: operator.gt, ast.GtE: operator.ge, ast.In: lambda a, b: a in b,
    ast.NotIn: lambda a, b: a not in b, ast.Is: operator.is_, ast.IsNot: operator.is_not,
}
_FUNCTIONS: dict[str, Callable[..., Any]] = {
    "len": len, "abs": abs, "min": min, "max": max, "int": int, "float": float, "str": str,
    "bool": bool, "round": round,
}
_METHODS = {"to_sec", "to_nsec", "startswith", "endswith", "lower", "upper", "strip"}


class ExpressionError(Exception):
    """The expression is malformed or uses something not allowed."""


@dataclass(frozen=True)
class Expression:
    """A checked expression; ``evaluate(names)`` computes it."""

    text: str
    tree: ast.Expression
    names: frozenset[str]

    def evaluate(self, values: dict[str, Any]) -> Any:
        try:
            return _eval(self.tree.body, values)
        except ExpressionError:
            raise
        except Exception as exc:  # a message without that field, a bad comparison...
            raise ExpressionError(f"{type(exc).__name__}: {exc}") from None


def compile_expression(text: str, names: frozenset[str]) -> Expression:
    """Parse and check ``text``: only the whitelist, only ``names`` as variables."""
    if len(text) > MAX_LENGTH:
        raise ExpressionError(f"expression longer than {MAX_LENGTH} characters")
    try:
        tree = ast.parse(text.strip(), mode="eval")
    except SyntaxError as exc:
        raise ExpressionError(f"syntax error at column {exc.offset}: {exc.msg}") from None
    for node in ast.walk(tree):
        _check(node, names)
    return Expression(text, tree, names)


_ALLOWED = (ast.Expression, ast.Constant, ast.Name, ast.Load, ast.Attribute, ast.Subscript,
            ast.Slice, ast.BinOp, ast.UnaryOp, ast.BoolOp, ast.And, ast.Or, ast.Compare,
            ast.IfExp, ast.Call, ast.Tuple, ast.List, *_BINOPS, *_UNARY, *_COMPARE)


def _check(node: ast.AST, names: frozenset[str]) -> None:
    if not isinstance(node, _ALLOWED):
        raise ExpressionError(f"'{type(node).__name__}' is not allowed in a filter expression")
    if isinstance(node, ast.Name) and node.id not in names and node.id not in _FUNCTIONS:
        raise ExpressionError(f"unknown name '{node.id}' (known: {', '.join(sorted(names))})")
    if isinstance(node, ast.Attribute) and node.attr.startswith("_"):
        raise ExpressionError(f"attribute '{node.attr}' is not allowed")
    if isinstance(node, ast.Call):
        if node.keywords:
            raise ExpressionError("keyword arguments are not allowed")
        func = node.func
        if isinstance(func, ast.Name):
            if func.id not in _FUNCTIONS:
                raise ExpressionError(f"function '{func.id}' is not allowed")
        elif not isinstance(func, ast.Attribute):
            raise ExpressionError("only named functions and methods may be called")
        elif func.attr not in _METHODS:
            raise ExpressionError(f"method '{func.attr}' is not allowed (allowed: "
                                  f"{', '.join(sorted(_METHODS))})")


def _eval(node: ast.AST, env: dict[str, Any]) -> Any:
    if isinstance(node, ast.Constant):
        return node.value
    if isinstance(node, ast.Name):
        return env[node.id] if node.id in env else _FUNCTIONS[node.id]
    if isinstance(node, ast.Attribute):
        return getattr(_eval(node.value, env), node.attr)
    if isinstance(node, ast.Subscript):
        return _eval(node.value, env)[_eval(node.slice, env)]
    if isinstance(node, ast.Slice):
        return slice(*(None if p is None else _eval(p, env)
                       for p in (node.lower, node.upper, node.step)))
    if isinstance(node, ast.BinOp):
        return _BINOPS[type(node.op)](_eval(node.left, env), _eval(node.right, env))
    if isinstance(node, ast.UnaryOp):
        return _UNARY[type(node.op)](_eval(node.operand, env))
    if isinstance(node, ast.BoolOp):
        if isinstance(node.op, ast.And):
            result: Any = True
            for value in node.values:
                result = _eval(value, env)
                if not result:
                    return result
            return result
        result = False
        for value in node.values:
            result = _eval(value, env)
            if result:
                return result
        return result
    if isinstance(node, ast.Compare):
        left = _eval(node.left, env)
        for op, comp in zip(node.ops, node.comparators, strict=True):
            right = _eval(comp, env)
            if not _COMPARE[type(op)](left, right):
                return False
            left = right
        return True
    if isinstance(node, ast.IfExp):
        return _eval(node.body if _eval(node.test, env) else node.orelse, env)
    if isinstance(node, ast.Call):
        func = _eval(node.func, env)
        return func(*(_eval(a, env) for a in node.args))
    if isinstance(node, (ast.Tuple, ast.List)):
        return tuple(_eval(e, env) for e in node.elts)
    raise ExpressionError(f"'{type(node).__name__}' is not allowed")
