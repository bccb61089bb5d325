"""``$(eval EXPR)``: launch files' expressions, evaluated by ``orchestra.expression``.

roslaunch hands the text to Python's ``eval`` with only ``__`` banned; here it goes to the
one safe evaluator with the launch policy: the launch args as variables (typed like
roslaunch: ``'3'`` is 3, ``'false'`` is False), the launch functions ``arg env optenv find
anon dirname`` (supplied by the caller), ``true``/``false`` and math's constants, every
builtin and ``math`` function the evaluator offers, every ``str`` method it guards, no
attribute reads, and roslaunch's own ban on ``__`` so a file orchestra accepts is one
roslaunch accepts. What is allowed and the bounds are documented in docs/compat.md.
"""
from __future__ import annotations

import ast
import math
from collections.abc import Callable, Iterator, Mapping
from typing import Any

from orchestra import expression
from orchestra.errors import OrchestraError, clip
from orchestra.expression import MAX_EXPRESSION, STR_METHODS, ExpressionError

__all__ = ["CONSTANTS", "LAUNCH_FUNCTIONS", "MAX_EXPRESSION", "NAMES", "POLICY", "STR_METHODS",
           "EvalError", "evaluate", "parse_tree", "problem"]

LAUNCH_FUNCTIONS = ("arg", "anon", "dirname", "env", "find", "optenv")
CONSTANTS: dict[str, Any] = {"true": True, "false": False, "True": True, "False": False,
                             "None": None, "pi": math.pi, "e": math.e, "tau": math.tau,
                             "inf": math.inf, "nan": math.nan}

POLICY = expression.Policy(
    functions=expression.BUILTINS, str_methods=STR_METHODS, constants=CONSTANTS,
    no_double_underscore=True, passthrough=(OrchestraError,),
    known_names="the launch args, arg(), env(), optenv(), find(), anon(), dirname(), "
                "true/false and the builtins and math functions orchestra documents")

# Every name an expression may use besides the launch args, exported once for the checker.
NAMES = frozenset(LAUNCH_FUNCTIONS) | frozenset(CONSTANTS) | expression.BUILTINS


class EvalError(OrchestraError):
    """An ``$(eval)`` expression that is refused or fails (the caller adds file:line)."""


class _TypedArgs(Mapping[str, Any]):
    """The launch args as variables, each typed only when the expression names it."""

    def __init__(self, args: Mapping[str, str], convert: Callable[[str], Any]):
        self._args = args
        self._convert = convert

    def __getitem__(self, name: str) -> Any:
        return self._convert(self._args[name])

    def __contains__(self, name: object) -> bool:
        return name in self._args

    def __iter__(self) -> Iterator[str]:
        return iter(self._args)

    def __len__(self) -> int:
        return len(self._args)


def parse_tree(expr: str) -> ast.Expression | None:
    """The AST of ``expr``, or None when it is not an expression (nothing is evaluated)."""
    try:
        return expression.parse(expr, POLICY)
    except ExpressionError:
        return None


def problem(expr: str) -> str | None:
    """Why ``expr`` can never be evaluated (syntax, refused grammar), or None; nothing runs.

    For ``orchestra check``: what depends on values (sizes, unset args) is left to evaluation.
    """
    try:
        expression.validate(expression.parse(expr, POLICY), POLICY)
    except ExpressionError as exc:
        return f"$(eval {clip(expr)}): {exc}"
    return None


def evaluate(expr: str, args: Mapping[str, str], launch: Mapping[str, Callable[..., Any]],
             convert: Callable[[str], Any]) -> str:
    """The text of ``expr``'s value. ``launch`` implements ``LAUNCH_FUNCTIONS``; ``convert``
    types an arg's text the way bare names are typed. Raises ``EvalError`` (or the
    ``OrchestraError`` a launch function raised) for anything refused or failing."""
    try:
        tree = _checked_tree(expr)
        functions = {name: launch[name] for name in LAUNCH_FUNCTIONS}
        value = expression.evaluate(tree, POLICY, _TypedArgs(args, convert), functions)
        return expression.text_of(value)
    except ExpressionError as exc:
        raise EvalError(f"$(eval {clip(expr)}): {exc}") from None


# Parsed and validated expressions by text: the same few (``$(eval arg('x') == 'y')``) recur
# on many elements and in every file of a package, and the tree depends on the text alone
# (the evaluator only reads it). Only accepted texts are kept; emptied past the limit.
_TREES: dict[str, ast.Expression] = {}
_TREES_LIMIT = 1024


def _checked_tree(expr: str) -> ast.Expression:
    tree = _TREES.get(expr)
    if tree is None:
        tree = expression.parse(expr, POLICY)
        expression.validate(tree, POLICY)
        if len(_TREES) >= _TREES_LIMIT:
            _TREES.clear()
        _TREES[expr] = tree
    return tree
