"""The YAML front end: a roslaunch tag tree written in YAML, read into the same Entities as XML.

Why YAML at all: it is the same launch language (same tags, same attributes, same ``$(...)``
substitutions, one interpreter), only without angle brackets, so a user can choose the syntax
and ``orchestra convert`` can move a file between the two without changing what it launches.
The schema is documented in docs/launch-yaml.md; in short::

    launch:
      - arg: {name: robot, default: turtle}
      - node:
          pkg: turtlesim
          type: turtlesim_node
          name: sim
          children:
            - param: {name: speed, value: 2.0}
      - rosparam:
          command: load
          text: |
            gains: {p: 1.0}

Losslessness is the design constraint. An attribute value is the *text* of the YAML scalar
exactly as written (after quote/escape processing), never a constructed Python value:
``respawn: true`` is "true", ``value: 1.10`` is "1.10" (not "1.1"), ``default: ~`` is "~",
and ``default:`` (nothing) is "". That is what the XML would have held, so both front ends
give the interpreter the same strings. The document is *composed*, never constructed, so no
YAML tag can build an object; tags outside YAML's core schema (``!!python/object``...) are
refused outright.
"""
from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import yaml as pyyaml
from yaml.nodes import MappingNode, Node, ScalarNode, SequenceNode

from orchestra.errors import Location, OrchestraError, offset_location
from orchestra.launch.entity import Entity
from orchestra.params.yaml import char_name as _char_name
from orchestra.params.yaml import reader_error_location


@dataclass(frozen=True)
class KnownPositions:
    """Positions this front end had at hand while reading (YAML marks): the
    ``entity.SourcePositions`` of a YAML element. (Here, not in entity.py: only YAML files
    need the class, and every launch process would otherwise build it, ~5 M instructions.)"""

    start_at: Location
    attributes: Mapping[str, Location]

    def start(self, entity: Entity) -> Location:
        return self.start_at

    def attribute(self, entity: Entity, name: str) -> Location | None:
        return self.attributes.get(name)


# The element key holding the element's own text (inline rosparam YAML).
TEXT_KEY = "text"
# The element key holding the element's children, in order.
CHILDREN_KEY = "children"
# Keys that are never attributes; converting an XML element that has an attribute of this
# name to YAML is refused (no roslaunch tag has one).
RESERVED_KEYS = frozenset({TEXT_KEY, CHILDREN_KEY})

# ROS 2 launch_yaml spellings accepted on input, per tag, mapped to the roslaunch attribute
# of the same meaning. ``orchestra convert`` always writes the roslaunch spelling.
ATTRIBUTE_ALIASES: dict[str, dict[str, str]] = {
    "node": {"exec": "type", "namespace": "ns", "launch_prefix": "launch-prefix"},
    "test": {"exec": "type", "namespace": "ns", "launch_prefix": "launch-prefix"},
    "group": {"namespace": "ns"},
    "include": {"namespace": "ns"},
    "arg": {"description": "doc"},
}

# Tags a YAML key may name as children (``param: [{...}, {...}]`` in ROS 2 style). Knowing
# them lets a mis-typed structured attribute value (``value: [1, 2]``) get a precise error
# instead of silently turning into an unknown child element.
LAUNCH_TAGS = frozenset({
    "launch", "node", "test", "param", "rosparam", "remap", "include", "group", "arg",
    "env", "machine", "master",
})

_CORE_TAG_PREFIX = "tag:yaml.org,2002:"
_CORE_TAGS = frozenset(_CORE_TAG_PREFIX + name for name in (
    "str", "int", "float", "bool", "null", "map", "seq", "merge", "timestamp", "value",
))

# libyaml's composer when PyYAML was built with it (much faster than the pure-Python one, and
# ``orchestra launch`` start-up time matters); same nodes, tags and marks as the pure one.
_LOADER = getattr(pyyaml, "CSafeLoader", pyyaml.SafeLoader)

class LaunchYamlError(OrchestraError):
    """A YAML launch file that is not valid YAML or not the launch schema."""


def _location(filename: str, node: Node) -> Location:
    mark = node.start_mark
    return Location(filename, mark.line + 1, mark.column + 1)


def parse_file(path: str) -> Entity:
    """Read a YAML launch file into its root Entity (normally ``launch``)."""
    from orchestra.launch.files import read_text  # symlink stubs, as the XML front end

    try:
        text = read_text(path)
    except FileNotFoundError:
        raise LaunchYamlError("launch file not found", Location(path)) from None
    except UnicodeDecodeError as exc:
        raise LaunchYamlError(f"not UTF-8: byte 0x{exc.object[exc.start]:02x} cannot be "
                              f"decoded ({exc.reason})",
                              offset_location(path, exc.object, exc.start)) from None
    except OSError as exc:
        raise LaunchYamlError(f"cannot read launch file: {exc}", Location(path)) from None
    return parse_string(text, path)


def parse_string(text: str, filename: str = "<string>") -> Entity:
    """Read YAML launch text; ``filename`` is only used for locations in Entities and errors."""
    root = _compose(text, filename)
    if root is None:
        raise LaunchYamlError("empty launch file: expected 'launch:' at the top",
                              Location(filename, 1, 1))
    _refuse_foreign_tags(root, filename)
    if not isinstance(root, MappingNode) or len(root.value) != 1:
        raise LaunchYamlError(
            "a YAML launch file must be one mapping with the single key 'launch:' "
            "(for example 'launch: [...]')", _location(filename, root))
    key, body = root.value[0]
    try:
        return _element(_key_text(key, filename), key, body, filename, _Guard())
    except RecursionError:
        # nesting (or a self-merging `<<: *x`) deeper than Python's stack: refuse, no trace
        raise LaunchYamlError("the document nests too deeply to be a launch file",
                              _location(filename, root)) from None


def _compose(text: str, filename: str) -> Node | None:
    """Compose (never construct) the single document of ``text``, with positions."""
    try:
        documents = list(pyyaml.compose_all(text, Loader=_LOADER))
    except pyyaml.MarkedYAMLError as exc:
        mark = exc.problem_mark or exc.context_mark
        where = Location(filename, mark.line + 1, mark.column + 1) if mark else Location(filename)
        problem = exc.problem or "invalid YAML"
        context = f" ({exc.context})" if exc.context else ""
        raise LaunchYamlError(f"invalid YAML: {problem}{context}", where) from None
    except pyyaml.reader.ReaderError as exc:
        raise LaunchYamlError(f"invalid YAML: character {_char_name(exc.character)} is not "
                              f"allowed ({exc.reason})",
                              reader_error_location(exc, text, filename, _LOADER)) from None
    except pyyaml.YAMLError as exc:
        raise LaunchYamlError(f"invalid YAML: {exc}", Location(filename, 1, 1)) from None
    documents = [doc for doc in documents if doc is not None]
    if len(documents) > 1:
        raise LaunchYamlError("a YAML launch file holds exactly one document (found a second "
                              "'---')", _location(filename, documents[1]))
    return documents[0] if documents else None


def _refuse_foreign_tags(root: Node, filename: str) -> None:
    """Refuse any tag outside YAML's core schema anywhere in the document.

    Nothing is ever constructed, so such a tag could not execute code here; refusing it is
    about meaning: a launch file saying ``!!python/object`` expects something orchestra will
    never do, and silently reading it as a string would hide that.
    """
    seen: set[int] = set()
    stack = [root]
    while stack:
        node = stack.pop()
        if id(node) in seen:
            continue
        seen.add(id(node))
        if node.tag not in _CORE_TAGS:
            shown = node.tag.replace(_CORE_TAG_PREFIX, "!!", 1)
            raise LaunchYamlError(f"YAML tag '{shown}' is not allowed in a launch file "
                                  "(only plain scalars, mappings and lists; rosparam YAML "
                                  "with its own tags goes in a 'text: |' block)",
                                  _location(filename, node))
        if isinstance(node, SequenceNode):
            stack.extend(node.value)
        elif isinstance(node, MappingNode):
            for key, value in node.value:
                stack.extend((key, value))


def _key_text(key: Node, filename: str) -> str:
    if not isinstance(key, ScalarNode) or key.value == "":
        raise LaunchYamlError("a key must be a plain name (a tag or attribute name)",
                              _location(filename, key))
    return key.value


class _Guard:
    """Stops YAML aliases from expanding forever (``&a [*a]``) or exponentially (a few
    nested aliases repeated: the "billion laughs"): Entities are a tree, aliases are copied."""

    MAX_ELEMENTS = 20_000  # real launch trees hold hundreds

    def __init__(self) -> None:
        self.active: set[int] = set()
        self.count = 0

    def enter(self, node: Node, filename: str) -> None:
        if id(node) in self.active:
            raise LaunchYamlError("a YAML alias refers to an element that contains it "
                                  "(recursive alias)", _location(filename, node))
        self.count += 1
        if self.count > self.MAX_ELEMENTS:
            raise LaunchYamlError(f"more than {self.MAX_ELEMENTS} elements after expanding "
                                  "YAML aliases", _location(filename, node))
        self.active.add(id(node))

    def leave(self, node: Node) -> None:
        self.active.discard(id(node))


def _element(tag: str, key: Node, body: Node, filename: str, guard: _Guard) -> Entity:
    """One element: ``tag`` written at ``key`` with ``body`` (attributes/children/text)."""
    guard.enter(body, filename)
    try:
        return _element_body(tag, key, body, filename, guard)
    finally:
        guard.leave(body)


def _element_body(tag: str, key: Node, body: Node, filename: str, guard: _Guard) -> Entity:
    entity = Entity(tag=tag, location=_location(filename, key))
    attribute_locations: dict[str, Location] = {}
    entity.positions = KnownPositions(entity.location, attribute_locations)
    if isinstance(body, ScalarNode):
        if body.tag == _CORE_TAG_PREFIX + "null" and body.value in ("", "~", "null", "Null",
                                                                    "NULL"):
            return entity  # `- group:` : an element with nothing in it
        raise LaunchYamlError(
            f"<{tag}> must hold a mapping of attributes, a list of children or nothing; "
            f"got the value '{body.value}' (element text goes under '{TEXT_KEY}:')",
            _location(filename, body))
    if isinstance(body, SequenceNode):
        entity.children.extend(_children(body, filename, guard, list_of=tag))
        return entity
    assert isinstance(body, MappingNode)  # scalar and sequence bodies returned above
    aliases = ATTRIBUTE_ALIASES.get(tag, {})
    for item_key, value in _mapping_items(body, filename):
        name = _key_text(item_key, filename)
        where = _location(filename, item_key)
        if name == CHILDREN_KEY:
            if not isinstance(value, SequenceNode):
                raise LaunchYamlError(f"'{CHILDREN_KEY}:' of <{tag}> must be a list of "
                                      "elements", _location(filename, value))
            entity.children.extend(_children(value, filename, guard))
        elif name == TEXT_KEY:
            if not isinstance(value, ScalarNode):
                raise LaunchYamlError(f"'{TEXT_KEY}:' of <{tag}> must be a string (use a "
                                      "'|' block for inline YAML)", _location(filename, value))
            entity.text = value.value
        elif isinstance(value, ScalarNode):
            canonical = aliases.get(name, name)
            if canonical in entity.attributes:
                raise LaunchYamlError(f"attribute '{canonical}' of <{tag}> is given twice"
                                      + (f" (as '{name}')" if canonical != name else ""),
                                      where)
            entity.attributes[canonical] = value.value
            attribute_locations[canonical] = where
        elif name in LAUNCH_TAGS:
            # ROS 2 style: `param: [{name: a, value: 1}]` or `remap: {from: a, to: b}`
            if isinstance(value, SequenceNode):
                for item in value.value:
                    entity.children.append(_element(name, item, item, filename, guard))
            else:
                entity.children.append(_element(name, item_key, value, filename, guard))
        else:
            raise LaunchYamlError(
                f"attribute '{name}' of <{tag}> must be a single value, not a "
                f"{'list' if isinstance(value, SequenceNode) else 'mapping'} (quote it to "
                f"pass YAML text: {name}: '[1, 2]')", _location(filename, value))
    return entity


def _mapping_items(node: MappingNode, filename: str) -> list[tuple[Node, Node]]:
    """The mapping's pairs with YAML merge keys (``<<: *defaults``) applied; duplicates refused."""
    if any(key.tag == _CORE_TAG_PREFIX + "merge" for key, _ in node.value):
        merged = MappingNode(node.tag, list(node.value), node.start_mark, node.end_mark)
        try:
            pyyaml.SafeLoader("").flatten_mapping(merged)
        except pyyaml.MarkedYAMLError as exc:
            mark = exc.problem_mark
            raise LaunchYamlError(f"invalid merge key: {exc.problem}",
                                  Location(filename, mark.line + 1, mark.column + 1)
                                  if mark else _location(filename, node)) from None
        own_count = sum(1 for key, _ in node.value if key.tag != _CORE_TAG_PREFIX + "merge")
        pairs = _last_wins_for_merged(merged.value, len(merged.value) - own_count)
    else:
        pairs = list(node.value)
    seen: dict[str, Node] = {}
    for key, _ in pairs:
        name = key.value if isinstance(key, ScalarNode) else None
        if name is not None and name in seen:
            first = seen[name].start_mark.line + 1
            raise LaunchYamlError(f"duplicate key '{name}' (first written on line {first})",
                                  _location(filename, key))
        if name is not None:
            seen[name] = key
    return pairs


def _last_wins_for_merged(pairs: list[tuple[Node, Node]], merged_count: int
                          ) -> list[tuple[Node, Node]]:
    """Keys merged in with ``<<`` are overridden by keys written in the mapping itself."""
    own = {key.value for key, _ in pairs[merged_count:] if isinstance(key, ScalarNode)}
    result: list[tuple[Node, Node]] = []
    merged_seen: set[str] = set()
    for index, (key, value) in enumerate(pairs):
        name = key.value if isinstance(key, ScalarNode) else None
        if index < merged_count:
            if name in own or name in merged_seen:
                continue
            if name is not None:
                merged_seen.add(name)
        result.append((key, value))
    return result


def _children(sequence: SequenceNode, filename: str, guard: _Guard,
              list_of: str | None = None) -> list[Entity]:
    """A list of ``- tag: body`` items (nested lists are flattened in place).

    ``list_of`` is the tag whose body this list is (``- group: [...]``), for the error hint
    when someone meant several elements of that tag.
    """
    children: list[Entity] = []
    for item in sequence.value:
        children.extend(_child(item, filename, guard, list_of))
    return children


def _child(item: Node, filename: str, guard: _Guard, list_of: str | None) -> list[Entity]:
    """The element(s) of one list item."""
    if isinstance(item, SequenceNode):
        guard.enter(item, filename)
        try:
            return _children(item, filename, guard, list_of)
        finally:
            guard.leave(item)
    if not isinstance(item, MappingNode) or len(item.value) != 1:
        hint = ""
        if list_of and isinstance(item, MappingNode):
            hint = (f"; a list under '{list_of}:' holds the children of one <{list_of}>"
                    f" — for several <{list_of}> elements write one '- {list_of}:' item each")
        raise LaunchYamlError(
            "each list item must be one element written as '- tag: {attributes}' "
            "(a mapping with exactly one key)" + hint, _location(filename, item))
    key, body = item.value[0]
    return [_element(_key_text(key, filename), key, body, filename, guard)]
