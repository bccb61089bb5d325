"""The ``.msg`` / ``.srv`` language: parse definitions, compute md5 sums and full texts.

These are the ROS 1 (genmsg) rules, kept as pure functions so they can be checked against
the md5 sums of the standard messages: the md5 of a message is taken over its constants and
fields with every nested message type replaced by that type's own md5; a service's md5 is
taken over the request text followed by the response text. The "full text" sent in
connection headers is the definition followed by each dependency's definition.
"""
from __future__ import annotations

import hashlib
import keyword
import re
from collections.abc import Callable
from dataclasses import dataclass, field

from orchestra.node.exceptions import ROSException

# ROS primitive -> struct format character
PRIMITIVES: dict[str, str] = {
    "bool": "B", "int8": "b", "uint8": "B", "byte": "b", "char": "B",
    "int16": "h", "uint16": "H", "int32": "i", "uint32": "I",
    "int64": "q", "uint64": "Q", "float32": "f", "float64": "d",
}
BUILTINS = frozenset(PRIMITIVES) | {"string", "time", "duration"}
SEPARATOR = "=" * 80
_FIELD_NAME = re.compile(r"^[A-Za-z][A-Za-z0-9_]*$")
_TYPE = re.compile(r"^([A-Za-z][A-Za-z0-9_]*/)?[A-Za-z][A-Za-z0-9_]*(\[\d*\])?$")


class MsgSpecError(ROSException):
    """A ``.msg``/``.srv`` definition that does not follow the language."""


@dataclass(frozen=True)
class Field:
    """One field: ``base`` is a builtin or ``pkg/Type``; ``array`` None, -1 (variable) or N."""

    name: str
    base: str
    array: int | None = None
    line: int = field(default=0, compare=False)  # where it is defined, for error messages

    @property
    def is_builtin(self) -> bool:
        return self.base in BUILTINS

    @property
    def type_text(self) -> str:
        """The type as genmsg writes it (``float64[9]``, ``geometry_msgs/Point[]``)."""
        if self.array is None:
            return self.base
        return f"{self.base}[{'' if self.array < 0 else self.array}]"


@dataclass(frozen=True)
class Constant:
    type: str
    name: str
    value: object
    text: str


@dataclass(frozen=True)
class MsgSpec:
    """A parsed message definition; ``text`` is the source, kept for the full text."""

    type: str
    fields: tuple[Field, ...]
    constants: tuple[Constant, ...]
    text: str
    source: str = field(default="", compare=False)  # the definition's file ('' if none)

    def where(self, f: Field | None = None) -> str:
        """``file:line`` (or the type name) of the definition, or of one of its fields."""
        head = self.source or self.type
        return f"{head}:{f.line}" if f is not None and f.line else head

    @property
    def package(self) -> str:
        return self.type.split("/")[0]

    def dependencies(self) -> list[str]:
        """Nested message types, in order of first use."""
        seen: list[str] = []
        for f in self.fields:
            if not f.is_builtin and f.base not in seen:
                seen.append(f.base)
        return seen


@dataclass(frozen=True)
class SrvSpec:
    type: str
    request: MsgSpec
    response: MsgSpec
    text: str


def _resolve_type(base: str, package: str) -> str:
    if base in BUILTINS:
        return base
    if base == "Header":
        return "std_msgs/Header"
    if "/" in base:
        return base
    return f"{package}/{base}"


def _constant_value(ctype: str, text: str, where: str):
    if ctype == "string":
        return text
    try:
        if ctype == "bool":
            return text.strip().lower() in ("true", "1")
        if ctype in ("float32", "float64"):
            return float(text)
        return int(text, 0) if text.strip().lower().startswith(("0x", "0o", "0b")) else int(text)
    except ValueError:
        raise MsgSpecError(f"{where}: bad value {text!r} for constant of type {ctype}") from None


def parse_msg(text: str, msg_type: str, source: str | None = None,
              first_line: int = 1) -> MsgSpec:
    """Parse a ``.msg`` body; ``msg_type`` is ``pkg/Name`` (relative types live in ``pkg``).

    ``first_line`` is the file line of the body's first line (the halves of a ``.srv`` or
    ``.action`` file), so errors name the line a user sees in the file."""
    package = msg_type.split("/")[0]
    fields: list[Field] = []
    constants: list[Constant] = []
    names: set[str] = set()
    for lineno, raw in enumerate(text.splitlines(), first_line):
        where = f"{source or msg_type}:{lineno}"
        line = raw.strip()
        if not line or line.startswith("#"):
            continue
        parts = line.split(None, 1)
        if len(parts) < 2:
            raise MsgSpecError(f"{where}: expected 'type name', got {line!r}")
        type_text, rest = parts
        if not _TYPE.match(type_text):
            raise MsgSpecError(f"{where}: bad type {type_text!r}")
        if "=" in rest.split("#", 1)[0] or (type_text == "string" and "=" in rest):
            name, value = rest.split("=", 1)
            name = name.strip()
            value = value.strip() if type_text == "string" else value.split("#", 1)[0].strip()
            if type_text not in PRIMITIVES and type_text != "string":
                raise MsgSpecError(f"{where}: constants must be primitive, not {type_text}")
            constants.append(Constant(type_text, name, _constant_value(type_text, value, where), value))
            continue
        name = rest.split("#", 1)[0].strip()
        if not _FIELD_NAME.match(name):
            raise MsgSpecError(f"{where}: bad field name {name!r}")
        if name in names:
            raise MsgSpecError(f"{where}: duplicate field {name!r}")
        if keyword.iskeyword(name):
            raise MsgSpecError(f"{where}: field name {name!r} is a Python keyword "
                               "(not supported by orchestra's message classes)")
        names.add(name)
        array: int | None = None
        base = type_text
        if base.endswith("]"):
            base, size = base[:-1].split("[", 1)
            array = int(size) if size else -1
        fields.append(Field(name, _resolve_type(base, package), array, lineno))
    return MsgSpec(msg_type, tuple(fields), tuple(constants), text, source or "")


def split_sections(text: str, count: int, what: str, source: str | None = None
                   ) -> list[tuple[str, int]]:
    """The ``count`` parts of a ``.srv`` (2) or ``.action`` (3) body, split at ``---`` lines,
    each with the file line its text starts on."""
    parts: list[tuple[str, int]] = []
    start, lines = 0, text.splitlines(keepends=True)
    for i, line in enumerate(lines):
        if line.strip() == "---":
            parts.append(("".join(lines[start:i]), start + 1))
            start = i + 1
    parts.append(("".join(lines[start:]), start + 1))
    if len(parts) != count:
        raise MsgSpecError(f"{source or what}:{max(len(lines), 1)}: a {what} definition has "
                           f"{count - 1} '---' "
                           f"line{'s' if count > 2 else ''} between its parts, found "
                           f"{len(parts) - 1}")
    return parts


def split_srv(text: str) -> tuple[str, str]:
    """The request and response halves of a ``.srv`` body (split at the ``---`` line)."""
    (req, _), (resp, _) = split_sections(text, 2, "service")
    return req, resp


def parse_srv(text: str, srv_type: str, source: str | None = None) -> SrvSpec:
    (req, l1), (resp, l2) = split_sections(text, 2, "service", source)
    return SrvSpec(srv_type, parse_msg(req, srv_type + "Request", source, l1),
                   parse_msg(resp, srv_type + "Response", source, l2), text)


ACTION_BANNER = "# ====== DO NOT MODIFY! AUTOGENERATED FROM AN ACTION DEFINITION ======\n"


def action_message_texts(text: str, action_type: str, source: str | None = None
                         ) -> dict[str, tuple[str, int]]:
    """The seven message definitions genaction derives from one ``.action`` file:
    ``<A>Goal``/``Result``/``Feedback`` (the three parts, with their first file line) and the
    ``<A>Action``, ``<A>ActionGoal``/``ActionResult``/``ActionFeedback`` wrappers that carry
    them over actionlib's topics (line 0: they have no line of their own)."""
    name = action_type.split("/")[1]
    (goal, l1), (result, l2), (feedback, l3) = split_sections(text, 3, "action", source)
    b = ACTION_BANNER
    return {
        f"{action_type}Goal": (b + goal, l1 - 1),
        f"{action_type}Result": (b + result, l2 - 1),
        # genaction ends the last part with one more newline than the file has
        f"{action_type}Feedback": (b + feedback + "\n", l3 - 1),
        f"{action_type}Action": (
            f"{b}\n{name}ActionGoal action_goal\n{name}ActionResult action_result\n"
            f"{name}ActionFeedback action_feedback\n", 0),
        f"{action_type}ActionGoal": (
            f"{b}\nHeader header\nactionlib_msgs/GoalID goal_id\n{name}Goal goal\n", 0),
        f"{action_type}ActionResult": (
            f"{b}\nHeader header\nactionlib_msgs/GoalStatus status\n{name}Result result\n", 0),
        f"{action_type}ActionFeedback": (
            f"{b}\nHeader header\nactionlib_msgs/GoalStatus status\n"
            f"{name}Feedback feedback\n", 0),
    }


def parse_full_text(full_text: str, msg_type: str) -> dict[str, MsgSpec]:
    """Every definition in a connection header's ``message_definition`` (type -> spec)."""
    blocks = re.split(r"^={80}\s*$", full_text, flags=re.M)
    specs = {msg_type: parse_msg(blocks[0], msg_type)}
    for block in blocks[1:]:
        block = block.lstrip("\n")
        head, _, body = block.partition("\n")
        if not head.startswith("MSG:"):
            raise MsgSpecError(f"message definition of {msg_type}: block without 'MSG:' line")
        sub_type = head[4:].strip()
        specs[sub_type] = parse_msg(body, sub_type)
    return specs


Lookup = Callable[[str], MsgSpec]


def md5_text(spec: MsgSpec, lookup: Lookup, md5_of: Callable[[str], str] | None = None) -> str:
    """genmsg's md5 text: constants, then fields, nested types replaced by their md5."""
    md5_of = md5_of or (lambda t: compute_md5(lookup(t), lookup))
    lines = [f"{c.type} {c.name}={c.text}" for c in spec.constants]
    for f in spec.fields:
        if f.is_builtin:
            lines.append(f"{f.type_text} {f.name}")
        else:
            lines.append(f"{md5_of(f.base)} {f.name}")
    return "\n".join(lines).strip()


def compute_md5(spec: MsgSpec, lookup: Lookup, md5_of: Callable[[str], str] | None = None) -> str:
    return hashlib.md5(md5_text(spec, lookup, md5_of).encode()).hexdigest()


def compute_srv_md5(spec: SrvSpec, lookup: Lookup, md5_of: Callable[[str], str] | None = None) -> str:
    text = md5_text(spec.request, lookup, md5_of) + md5_text(spec.response, lookup, md5_of)
    return hashlib.md5(text.encode()).hexdigest()


def full_text(spec: MsgSpec, lookup: Lookup) -> str:
    """The definition followed by every (transitive) dependency, as sent in headers."""
    order: list[str] = []

    def visit(s: MsgSpec) -> None:
        for dep in s.dependencies():
            if dep not in order:
                order.append(dep)
                visit(lookup(dep))

    visit(spec)
    parts = [spec.text.rstrip("\n") + "\n"]
    for dep in order:
        parts.append(f"{SEPARATOR}\nMSG: {dep}\n{lookup(dep).text.rstrip(chr(10))}\n")
    return "".join(parts)
