"""``bag filter`` expressions, evaluated by ``orchestra.expression``.

rosbag filter runs its EXPR through Python's ``eval``: any code. Here it goes to the one safe
evaluator with the filter policy: the names given (``topic``, ``m``, ``t``), a few pure
built-ins, reads of the public attributes of messages and times (never a name starting with
``_``, and only data: a method is never a value), calls of the read-only methods of strings
and times listed below. Anything else is refused when the expression is compiled, before any
message is read, and every value the expression builds is bounded like ``$(eval)``'s.
"""
from __future__ import annotations

import ast
from dataclasses import dataclass
from typing import Any

from orchestra import expression
from orchestra.expression import ExpressionError
from orchestra.node.msg import Message
from orchestra.node.rostime import Duration, Time

__all__ = ["MAX_LENGTH", "POLICY", "Expression", "ExpressionError", "compile_expression"]

MAX_LENGTH = 2000
_FUNCTIONS = frozenset({"len", "abs", "min", "max", "int", "float", "str", "bool", "round"})


def _readable(value: Any) -> bool:
    """Messages and times: the objects whose fields a filter reads."""
    return isinstance(value, (Message, Time, Duration))


POLICY = expression.Policy(
    functions=_FUNCTIONS,
    str_methods=frozenset({"startswith", "endswith", "lower", "upper", "strip"}),
    readable=_readable, object_methods=frozenset({"to_sec", "to_nsec"}),
    max_expression=MAX_LENGTH,
    known_names=", ".join(f"{f}()" for f in sorted(_FUNCTIONS)))


@dataclass(frozen=True)
class Expression:
    """A checked expression; ``evaluate(values)`` computes it."""

    text: str
    tree: ast.Expression
    names: frozenset[str]

    def evaluate(self, values: dict[str, Any]) -> Any:
        """The value with ``values`` bound; ``ExpressionError`` when it fails."""
        return expression.evaluate(self.tree, POLICY, values)


def compile_expression(text: str, names: frozenset[str]) -> Expression:
    """Parse and check ``text``: only the policy's grammar, only ``names`` as variables."""
    tree = expression.parse(text, POLICY)
    expression.validate(tree, POLICY, names)
    return Expression(text, tree, names)
