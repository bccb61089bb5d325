"""The top-level ``<arg>``s a launch file declares, read without interpreting it: what
``orchestra launch --ros-args`` lists and shell completion offers.

Its own module, not the interpreter's: only these two ask, and every other launch process
would build the ``ArgInfo`` class (~5 M instructions of a ~60 ms process).
"""
from __future__ import annotations

import os
from dataclasses import dataclass

from orchestra.errors import OrchestraError
from orchestra.launch.context import Scope
from orchestra.launch.entity import Entity
from orchestra.launch.substitution import resolve


@dataclass(frozen=True)
class ArgInfo:
    """A top-level ``<arg>`` as ``--ros-args`` reports it."""

    name: str
    doc: str | None
    default: str | None


def declared_args(root: Entity, filename: str, args: dict[str, str] | None = None
                  ) -> list[ArgInfo]:
    """The top-level ``<arg>``s of a launch file without interpreting it (``--ros-args``).

    Like roslaunch's args-only mode this must work when required args are missing, so a
    substitution that cannot be resolved is shown as written.
    """
    scope = Scope(os.environ.get("ROS_NAMESPACE", "/") or "/", filename)
    scope.args = dict(args or {})
    found: list[ArgInfo] = []
    for entity in root.children:
        if entity.tag != "arg" or "name" not in entity.attributes:
            continue
        values: dict[str, str | None] = {}
        for attr in ("name", "value", "default", "doc"):
            raw = entity.attributes.get(attr)
            try:
                values[attr] = resolve(raw, scope)
            except OrchestraError:
                values[attr] = raw
        name = values["name"] or ""  # written (checked above), so resolved to a string
        if values["value"] is not None:
            scope.args.setdefault(name, values["value"])
            if values["value"]:
                continue
        elif values["default"] is not None:
            scope.args.setdefault(name, values["default"])
        found.append(ArgInfo(name, values["doc"], values["default"]))
    return found
