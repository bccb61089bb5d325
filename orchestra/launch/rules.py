"""The launch language's tag rules as data: tags, their attributes and children, value kinds.

One table, read by both the interpreter (which enforces it while resolving the branches the
args take) and ``orchestra check`` (which reports against it in every branch). Keeping the
rules here, and nowhere else, is what stops the checker and the interpreter from disagreeing
(a lint that accepts what launch then rejects, or the other way round). The rules are
roslaunch 1.16's (``xmlloader.py``): unknown tags and attributes are ignored with a warning,
required attributes are errors, ``if``/``unless`` accept ``true``/``false``/``1``/``0`` while
other booleans accept only ``true``/``false``.

Adding an attribute is one line in ``TAGS`` (its kind, whether it is required).
"""
from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from functools import cached_property, lru_cache
from types import MappingProxyType
from typing import NamedTuple

from orchestra.errors import Location, OrchestraError, clip
from orchestra.launch.plan import OUTPUT_MODES
from orchestra.launch.values import PARAM_TYPES, bool_attribute, convert_value, size_attribute

# ------------------------------------------------------------------------------ value kinds

class Kind(NamedTuple):
    """How an attribute's (resolved) text is read. ``parse`` raises ValueError with the
    reason for text of the wrong kind; its result is the typed value. (Kind and Attr are
    NamedTuples: constant table entries that every launch process builds the classes of,
    ~3x cheaper to create than frozen dataclasses' generated methods.)"""

    name: str
    parse: Callable[[str, str], object]  # (text, attribute name) -> value


def _text(text: str, label: str) -> str:
    return text


def _bool(text: str, label: str) -> bool:
    return bool_attribute(text, False, label)


def _condition(text: str, label: str) -> bool:
    return bool(convert_value(text, "bool"))


def _float(text: str, label: str) -> float:
    if not text:
        raise ValueError(f"value for {label} must be non-empty")
    try:
        return float(text)
    except ValueError:
        raise ValueError(f"invalid float value for {label}: {clip(text)}") from None


def _non_negative(text: str, label: str) -> float:
    value = _float(text, label)
    if value < 0:
        raise ValueError(f"must not be negative: {clip(text)}")
    return value


def _size(text: str, label: str) -> int | None:
    return size_attribute(text, None, label)


def _positive(text: str, label: str) -> float:
    if not text:
        raise ValueError("cannot be empty")
    try:
        value = float(text)
    except ValueError:
        raise ValueError(f"must be a number: [{clip(text)}]") from None
    if value <= 0:
        raise ValueError(f"must be a positive number: [{clip(text)}]")
    return value


def _int(text: str, label: str) -> int:
    try:
        return int(text)
    except ValueError:
        raise ValueError(f"must be a number: [{clip(text)}]") from None


def _port(text: str, label: str) -> int:
    try:
        return int(text or "22")
    except ValueError:
        raise ValueError(f"not a port number: {clip(text)}") from None


def _choice(*choices: str, fold: bool = False, empty: str | None = None
            ) -> Callable[[str, str], object]:
    """One of ``choices`` (compared lower-cased and stripped with ``fold``); empty text
    means ``empty`` when that is given."""
    def parse(text: str, label: str) -> str:
        value = text.strip().lower() if fold else text
        if not value and empty is not None:
            return empty
        if value not in choices:
            shown = ", ".join(f"'{c}'" for c in choices)
            raise ValueError(f"must be one of {shown} (not '{clip(text)}')")
        return value
    return parse


STRING = Kind("string", _text)
BOOL = Kind("bool", _bool)              # true / false, any case (roslaunch's _bool_attr)
CONDITION = Kind("condition", _condition)  # if / unless: true / false / 1 / 0
FLOAT = Kind("float", _float)
NON_NEGATIVE = Kind("non-negative", _non_negative)
SIZE = Kind("size", _size)  # bytes, or a number with kB/MB/GB/KiB/MiB/GiB
POSITIVE = Kind("positive", _positive)
INT = Kind("int", _int)


class Attr(NamedTuple):
    """One attribute of a tag: its kind and whether the tag requires it."""

    kind: Kind = STRING
    required: bool = False
    forbidden: bool = False  # known, but an error on this tag
    blank_is_unset: bool = False  # roslaunch reads `attr=""` as not written


@dataclass(frozen=True)
class TagRule:
    """What a tag may hold. ``attributes`` keep the table's order (required ones first)."""

    tag: str
    attributes: Mapping[str, Attr]
    children: tuple[str, ...] = ()
    # roslaunch lower-cases the tags of a <node>'s or <include>'s children (<Param> is a
    # <param> there), but not those of a <launch> or <group> body
    fold_children: bool = False

    # derived from ``attributes`` once, on first use: every element of every file asks
    @cached_property
    def allowed(self) -> frozenset[str]:
        return frozenset(self.attributes)

    @cached_property
    def required(self) -> tuple[str, ...]:
        return tuple(name for name, attr in self.attributes.items() if attr.required)

    @cached_property
    def forbidden(self) -> tuple[str, ...]:
        return tuple(name for name, attr in self.attributes.items() if attr.forbidden)

    def child_tag(self, tag: str) -> str | None:
        """The tag ``tag`` is read as inside this one, or None when it is not allowed here."""
        name = tag.lower() if self.fold_children else tag
        return name if name in self.children else None


def _attrs(attrs: dict[str, Attr]) -> Mapping[str, Attr]:
    """A tag's attributes in table order, plus ``if``/``unless``, which every tag takes."""
    return MappingProxyType({**attrs, "if": Attr(CONDITION), "unless": Attr(CONDITION)})


REQ = Attr(required=True)
CLEAR_PARAMS = Attr(BOOL, blank_is_unset=True)
FORBIDDEN = Attr(forbidden=True)
_NODE_CHILDREN = ("env", "param", "remap", "rosparam")
# the tags a <launch> or <group> body dispatches
SCOPE_CHILDREN = ("arg", "env", "group", "include", "machine", "master", "node", "param",
                  "remap", "rosparam", "test")

# rosmon's extensions, honoured by the supervisor (docs/compat.md), and the Node field each
# sets. Another rosmon attribute is one line here.
ROSMON_NODE_ATTRS: dict[str, Attr] = {
    "stop-timeout": Attr(NON_NEGATIVE), "memory-limit": Attr(SIZE),
    "cpu-limit": Attr(NON_NEGATIVE), "enable-coredumps": Attr(BOOL),
}
ROSMON_NODE_FIELDS = {name: name.replace("-", "_") for name in ROSMON_NODE_ATTRS}

_PROCESS_ATTRS = {
    "machine": Attr(), "args": Attr(),
    "cwd": Attr(Kind("cwd", _choice("ROS_HOME", "node", "ros_home"))),
    "ns": Attr(), "clear_params": CLEAR_PARAMS, "launch-prefix": Attr(), "required": Attr(BOOL),
    **ROSMON_NODE_ATTRS,
}

TAGS: Mapping[str, TagRule] = MappingProxyType({rule.tag: rule for rule in (
    TagRule("launch", _attrs({"deprecated": Attr()}), SCOPE_CHILDREN),
    TagRule("group", _attrs({"ns": Attr(), "clear_params": CLEAR_PARAMS}), SCOPE_CHILDREN),
    TagRule("node", _attrs({
        "pkg": REQ, "type": REQ, "name": REQ, **_PROCESS_ATTRS,
        "output": Attr(Kind("output", _choice(*OUTPUT_MODES))),
        "respawn": Attr(BOOL), "respawn_delay": Attr(FLOAT),
    }), _NODE_CHILDREN, fold_children=True),
    TagRule("test", _attrs({
        "pkg": REQ, "type": REQ, "test-name": REQ, "name": Attr(), **_PROCESS_ATTRS,
        "time-limit": Attr(POSITIVE, blank_is_unset=True), "retry": Attr(INT, blank_is_unset=True),
        # a test runs once, to its end, logging to its result file
        "respawn": FORBIDDEN, "respawn_delay": FORBIDDEN, "output": FORBIDDEN,
    }), _NODE_CHILDREN, fold_children=True),
    TagRule("machine", _attrs({
        "name": REQ, "address": REQ, "env-loader": Attr(), "ssh-port": Attr(Kind("port", _port)),
        "user": Attr(), "password": Attr(),
        "default": Attr(Kind("default", _choice("true", "false", "never", fold=True,
                                                 empty="false"))),
        "timeout": Attr(POSITIVE),
    })),
    TagRule("param", _attrs({
        "name": REQ, "value": Attr(),
        "type": Attr(Kind("type", _choice(*PARAM_TYPES, fold=True, empty="auto"))),
        "textfile": Attr(), "binfile": Attr(), "command": Attr(),
    })),
    TagRule("rosparam", _attrs({
        "command": Attr(Kind("command", _choice("load", "dump", "delete", empty="load"))),
        "ns": Attr(),
        "file": Attr(), "param": Attr(), "subst_value": Attr(BOOL),
    })),
    TagRule("arg", _attrs({"name": REQ, "value": Attr(), "default": Attr(), "doc": Attr()})),
    TagRule("include", _attrs({"file": REQ, "ns": Attr(), "clear_params": CLEAR_PARAMS,
                               "pass_all_args": Attr(BOOL)}), ("arg", "env"),
            fold_children=True),
    TagRule("remap", _attrs({"from": REQ, "to": REQ})),
    TagRule("env", _attrs({"name": REQ, "value": REQ})),
    # defunct: roslaunch warns and ignores it, if/unless included (they are not evaluated)
    TagRule("master", MappingProxyType({"auto": Attr(), "if": Attr(), "unless": Attr()})),
)})
"""Every tag of the launch language, by name."""


def rule(tag: str) -> TagRule | None:
    """The rule of ``tag``; a child tag as written (``<Param>`` in a ``<node>``) finds the
    rule of the tag it is read as."""
    return TAGS.get(tag) or TAGS.get(tag.lower())


def attribute(tag: str, name: str) -> Attr | None:
    found = rule(tag)
    return found.attributes.get(name) if found is not None else None


@lru_cache(maxsize=4096)
def parse(tag: str, name: str, text: str) -> object:
    """``text`` (already resolved) read as the kind the table gives ``tag``'s ``name``;
    ValueError says why it is not one. Unknown attributes are plain text; None for a blank
    value that means "not written".

    Kept per text: the table is fixed, a kind's parse depends on the text alone and gives
    an immutable value, and launch files repeat the same few values (``type``, ``output``,
    ``respawn``...) on every element."""
    attr = attribute(tag, name)
    if attr is None:
        return text
    if attr.blank_is_unset and not text:
        return None
    return attr.kind.parse(text, name)


def truth(tag: str, name: str, text: str) -> bool | None:
    """The boolean a bool or condition attribute holds, None when ``text`` is not one."""
    try:
        value = parse(tag, name, text)
    except ValueError:
        return None
    return value if isinstance(value, bool) else None


# ------------------------------------------------------------------------ structured errors

# codes shared by the interpreter and `orchestra check`
MISSING_ATTRIBUTE = "missing-attribute"
UNKNOWN_ATTRIBUTE = "unknown-attribute"
UNKNOWN_TAG = "unknown-tag"
BAD_VALUE = "bad-value"
IF_UNLESS = "if-unless"
FORBIDDEN_ATTRIBUTE = "forbidden-attribute"
INVALID = "launch"  # anything else the interpreter rejects


class LaunchError(OrchestraError):
    """A launch file roslaunch would reject (or that orchestra refuses for safety).

    Besides the printed ``file:line: message`` it carries what it is about as values (the
    ``tag``, the ``attribute``, a stable ``code`` and the ``exact`` position of the attribute
    when the front end knows it), so tools never parse the message text.
    """

    def __init__(self, message: str, location: Location | None = None, *,
                 tag: str | None = None, attribute: str | None = None,
                 code: str = INVALID, exact: Location | None = None):
        super().__init__(message, location)
        self.tag = tag
        self.attribute = attribute
        self.code = code
        self.exact = exact if exact is not None else location
