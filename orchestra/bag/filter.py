"""``bag filter IN OUT EXPR``: copy the messages for which EXPR is true.

EXPR sees ``topic`` (str), ``m`` (the decoded message) and ``t`` (its bag time, with
``to_sec()``/``to_nsec()``/``secs``/``nsecs``), as rosbag filter's does, but it is evaluated
by ``expression`` (a whitelist), never by ``eval``. Messages are decoded only when EXPR
mentions ``m``.
"""
from __future__ import annotations

import ast
from typing import Any

from orchestra.bag.expression import Expression, ExpressionError, compile_expression
from orchestra.bag.records import Connection
from orchestra.bag.rewrite import rewrite
from orchestra.node.decode import RawDecoder
from orchestra.node.rostime import Time

NAMES = frozenset({"topic", "m", "t"})


def make_filter(text: str) -> Expression:
    return compile_expression(text, NAMES)


def filter_bag(src: str, dst: str, expr: Expression, compression: str = "none") -> int:
    decoder = RawDecoder()
    needs_message = any(isinstance(n, ast.Name) and n.id == "m" for n in ast.walk(expr.tree))

    def keep(conn: Connection, stamp: int, data: bytes) -> bool:
        values: dict[str, Any] = {"topic": conn.topic, "t": Time(stamp // 1_000_000_000,
                                                 stamp % 1_000_000_000)}
        if needs_message:
            values["m"] = decoder.decode(conn.header, data)
        try:
            return bool(expr.evaluate(values))
        except ExpressionError as exc:
            raise ExpressionError(f"on the {conn.topic} message at {values['t'].to_sec():.6f}:"
                                  f" {exc}") from None

    return rewrite(src, dst, compression, keep)

