"""``orchestra convert``: move launch files between XML and YAML without changing their meaning.

Both directions go through the Entity tree (file -> Entity -> text), so a conversion is
exactly as lossless as the Entity: tags, attributes (raw strings, in order) and element text
survive byte for byte; XML comments, attribute quoting style and YAML anchors do not (the
Entity has no place for them).

Converting a single file leaves its ``<include file=...>`` references alone: the interpreter
reads mixed trees (an XML file may include a YAML file and the other way round), so the result
launches the same thing. Converting a directory converts every launch file in it and rewrites
an include whose file name is one of the files converted in the same run, so a package can be
moved over to YAML in one step; the original files are kept beside the new ones.
"""
from __future__ import annotations

import fnmatch
import glob
import os
import re
import textwrap
from dataclasses import dataclass

import yaml as pyyaml
from lxml import etree
from yaml.nodes import MappingNode, Node, ScalarNode, SequenceNode

from orchestra.errors import Location, OrchestraError
from orchestra.launch import yaml as yaml_frontend
from orchestra.launch.entity import Entity
from orchestra.launch.frontends import YAML, format_of, parse_string
from orchestra.launch.frontends import parse_file as load_entity

FORMATS = ("yaml", "xml")
_RESOLVER = pyyaml.resolver.Resolver()
_STR_TAG = "tag:yaml.org,2002:str"
_MAP_TAG = "tag:yaml.org,2002:map"
_SEQ_TAG = "tag:yaml.org,2002:seq"
# A leaf element is written on one line (`- arg: {name: x, default: 1}`) when it fits.
_FLOW_WIDTH = 100


class ConvertError(OrchestraError):
    """A file that cannot be converted (unreadable, or not expressible in the target)."""


Comments = dict[int, list[str]]
"""Comment lines written just before an element, keyed by ``id()`` of its Entity."""


def to_text(entity: Entity, fmt: str, comments: Comments | None = None) -> str:
    """The launch file text of ``entity`` in format ``fmt`` ("yaml" or "xml")."""
    if fmt == "yaml":
        return to_yaml(entity, comments)
    if fmt == "xml":
        return to_xml(entity, comments)
    raise ConvertError(f"unknown target format '{fmt}' (expected one of {', '.join(FORMATS)})")


# --------------------------------------------------------------------------- Entity -> YAML


class _IndentedDumper(pyyaml.SafeDumper):
    """Indents lists under their key (``launch:\\n  - node:``), as people write them by hand."""

    def increase_indent(self, flow: bool = False, indentless: bool = False) -> None:
        super().increase_indent(flow, False)


def _scalar(value: str, style: str | None = None) -> ScalarNode:
    # Tag the scalar with what YAML would read the plain text as: the serializer then sees
    # the plain form as implicit and writes `true`/`1.10` unquoted. The YAML front end reads
    # the scalar's text, not its type, so the string comes back unchanged either way.
    if style is None:
        tag = _RESOLVER.resolve(ScalarNode, value, (True, False))
    else:
        tag = _STR_TAG
    return ScalarNode(tag, value, style=style)


def _entity_node(entity: Entity) -> MappingNode:
    """``{tag: body}``: the one-key mapping that is a list item of the YAML schema."""
    return MappingNode(_MAP_TAG, [(_scalar(entity.tag), _body_node(entity))])


def significant_text(entity: Entity) -> str | None:
    """The element's text, or None when it is only whitespace.

    The XML front end hands over every character between the tags, so an element with
    children carries its indentation as text. That whitespace is layout, not content (no tag
    rule reads it), and keeping it would litter every converted YAML element with
    ``text: "\n  \n"``; so both writers drop whitespace-only text, and "lossless" means
    equal Entities once layout whitespace is taken as no text (``without_layout``).
    """
    text = entity.text
    return None if text is None or not text.strip() else text


def without_layout(entity: Entity) -> Entity:
    """A copy of ``entity`` with whitespace-only text removed throughout (see above)."""
    return Entity(tag=entity.tag, attributes=dict(entity.attributes),
                  children=[without_layout(child) for child in entity.children],
                  text=significant_text(entity), location=entity.location)


def _body_node(entity: Entity):
    for name in entity.attributes:
        if name in yaml_frontend.RESERVED_KEYS:
            raise ConvertError(f"<{entity.tag}> has an attribute named '{name}', which the "
                               "YAML schema reserves; it cannot be written as YAML",
                               entity.location)
    text = significant_text(entity)
    if not entity.attributes and text is None:
        if not entity.children:
            return _scalar("")  # `- group:` : nothing in it
        return _children_node(entity.children)
    pairs: list[tuple[Node, Node]] = [
        (_scalar(name), _scalar(value, "'" if value == "" else None))  # '' not !!null ''
        for name, value in entity.attributes.items()]
    if text is not None:
        style = "|" if "\n" in text else None
        pairs.append((_scalar(yaml_frontend.TEXT_KEY), _scalar(text, style)))
    if entity.children:
        pairs.append((_scalar(yaml_frontend.CHILDREN_KEY), _children_node(entity.children)))
    flow = (not entity.children and text is None
            and sum(len(k.value) + len(v.value) + 4 for k, v in pairs) < _FLOW_WIDTH)
    return MappingNode(_MAP_TAG, pairs, flow_style=flow)


def _children_node(children: list[Entity]) -> SequenceNode:
    return SequenceNode(_SEQ_TAG, [_entity_node(child) for child in children],
                        flow_style=False)


def to_yaml(entity: Entity, comments: Comments | None = None) -> str:
    """YAML launch text that the YAML front end reads back into an Entity equal to ``entity``.

    ``comments`` (from ``read_comments``) are written as ``#`` lines just above their element.
    """
    document = MappingNode(_MAP_TAG, [(_scalar(entity.tag), _body_node(entity))],
                           flow_style=False)
    text = pyyaml.serialize(document, Dumper=_IndentedDumper, allow_unicode=True,
                            width=_FLOW_WIDTH)
    if comments:
        text = _yaml_with_comments(text, entity, comments)
    return text


def _yaml_with_comments(text: str, entity: Entity, comments: Comments) -> str:
    """Insert comment lines above the lines the elements were written on.

    The emitter knows nothing of comments, so the text is read back (the reader gives each
    element's line and column, and reads the elements in the same order) and the comment
    lines go in above, indented like the element's ``-``.
    """
    reread = parse_string(text, "<converted>", YAML)
    lines = text.split("\n")
    inserts: list[tuple[int, list[str]]] = []
    for original, written in zip(_preorder(entity), _preorder(reread), strict=False):
        block = comments.get(id(original))
        if not block or written.location.line is None:
            continue
        column = written.location.column or 1
        indent = " " * (column - 3) if column >= 3 else ""
        inserts.append((written.location.line - 1,
                        [indent + ("# " + line if line else "#") for line in block]))
    for index, block in sorted(inserts, key=lambda item: item[0], reverse=True):
        lines[index:index] = block
    return "\n".join(lines)


def _preorder(entity: Entity):
    yield entity
    for child in entity.children:
        yield from _preorder(child)


# ---------------------------------------------------------------------------- Entity -> XML


def _xml_comment(lines: list[str], depth: int) -> etree._Comment:
    """An XML comment holding ``lines`` ("--" cannot appear in one, so it is spaced out)."""
    cleaned = [line.replace("--", "- -").replace("--", "- -") for line in lines]
    if len(cleaned) == 1:
        body = f" {cleaned[0]} "
    else:
        pad = "\n" + "  " * depth
        body = "".join(pad + "  " + line for line in cleaned) + pad
    return etree.Comment(body)


def _xml_element(entity: Entity, depth: int, comments: Comments) -> etree._Element:
    try:
        element = etree.Element(entity.tag)
    except ValueError:
        raise ConvertError(f"'{entity.tag}' is not a valid XML tag name",
                           entity.location) from None
    for name, value in entity.attributes.items():
        try:
            element.set(name, value)
        except ValueError:
            raise ConvertError(f"attribute '{name}' of <{entity.tag}> cannot be written as "
                               "XML (invalid name or value)", entity.location) from None
    text = significant_text(entity)
    # Indent children only when the element has no text of its own: the XML front end reads
    # text and the whitespace between children as one string, so indenting around real text
    # would change it.
    indent = "\n" + "  " * (depth + 1) if text is None else None
    try:
        element.text = text if text is not None else (indent if entity.children else None)
    except ValueError:
        raise ConvertError(f"the text of <{entity.tag}> cannot be written as XML (control "
                           "characters)", entity.location) from None
    for index, child in enumerate(entity.children):
        block = comments.get(id(child))
        if block:
            try:
                comment = _xml_comment(block, depth + 1)
            except ValueError:
                comment = None  # a comment XML cannot hold: dropped, it is only a comment
            if comment is not None:
                comment.tail = indent
                element.append(comment)
        sub = _xml_element(child, depth + 1, comments)
        if indent is not None:
            last = index == len(entity.children) - 1
            sub.tail = "\n" + "  " * depth if last else indent
        element.append(sub)
    return element


def to_xml(entity: Entity, comments: Comments | None = None) -> str:
    """XML launch text that the XML front end reads back into an Entity equal to ``entity``.

    ``comments`` (from ``read_comments``) are written as ``<!-- -->`` just before their
    element.
    """
    comments = comments or {}
    root = _xml_element(entity, 0, comments)
    header = ""
    if comments.get(id(entity)):
        try:
            header = etree.tostring(_xml_comment(comments[id(entity)], 0),
                                    encoding="unicode") + "\n"
        except ValueError:
            header = ""
    body = etree.tostring(root, encoding="unicode")
    return '<?xml version="1.0"?>\n' + header + body + "\n"


# -------------------------------------------------------------------------------- comments


def read_comments(path: str, root: Entity) -> Comments:
    """The comments written just before each element of the launch file ``path`` (whose
    Entity tree is ``root``), so that a conversion can carry them over.

    Only comments that directly precede an element are kept (with nothing but other comments
    and whitespace between): those are the ones that describe it. Others (after the last
    child of an element, inside rosparam text) have no element to travel with.
    """
    try:
        if format_of(path) == "yaml":
            return _yaml_comments(path, root)
        return _xml_comments(path, root)
    except (OSError, UnicodeDecodeError, etree.XMLSyntaxError, OrchestraError):
        return {}


def _comment_lines(text: str) -> list[str]:
    """A comment's lines without the indentation of the file it came from. A first line
    written on the opening ``<!--`` line is dedented on its own (its indentation is the
    opener's, not the block's)."""
    first, newline, rest = text.partition("\n")
    if first.strip() and newline:
        lines = [first.strip()] + textwrap.dedent(rest).split("\n")
    else:
        lines = textwrap.dedent(text.strip("\n")).split("\n")
    lines = [line.rstrip() for line in lines]
    while lines and not lines[0].strip():
        lines.pop(0)
    while lines and not lines[-1].strip():
        lines.pop()
    if len(lines) == 1:
        lines = [lines[0].strip()]
    return lines


def _xml_comments(path: str, root: Entity) -> Comments:
    from orchestra.launch.files import read_bytes

    parser = etree.XMLParser(resolve_entities=False, no_network=True, load_dtd=False,
                             remove_pis=True, remove_comments=False)
    tree = etree.fromstring(read_bytes(path), parser)
    launch = next((el for el in tree.iter() if isinstance(el.tag, str)
                   and el.tag == root.tag), None)
    if launch is None:
        return {}
    elements = [launch] + [el for el in launch.iterdescendants() if isinstance(el.tag, str)]
    entities = list(_preorder(root))
    if len(elements) != len(entities):
        return {}  # not the tree the front end read: carry nothing rather than misplace
    comments: Comments = {}
    for element, entity in zip(elements, entities, strict=False):
        block: list[str] = []
        for sibling in element.itersiblings(preceding=True):
            if isinstance(sibling.tag, str):
                break
            if sibling.tag is etree.Comment and sibling.text and sibling.text.strip():
                block[0:0] = _comment_lines(sibling.text)
        if block:
            comments[id(entity)] = block
    return comments


def _yaml_comments(path: str, root: Entity) -> Comments:
    from orchestra.launch.files import read_text

    lines = read_text(path).split("\n")
    comments: Comments = {}
    used_lines: set[int] = set()
    for entity in _preorder(root):
        line = entity.location.line
        if line is None or line in used_lines:
            continue  # several elements on one line: the comment above is the first one's
        used_lines.add(line)
        block: list[str] = []
        index = line - 2
        while index >= 0 and lines[index].lstrip().startswith("#"):
            text = lines[index].lstrip()[1:]
            block.insert(0, text[1:] if text.startswith(" ") else text)
            index -= 1
        while block and not block[0].strip():
            block.pop(0)
        if block:
            comments[id(entity)] = block
    return comments


# ------------------------------------------------------------------------------ whole files


def target_name(path: str, fmt: str) -> str:
    """Where the converted ``path`` goes: the source name plus ``.yaml`` (``x.launch`` ->
    ``x.launch.yaml``, ``x.launch.xml`` -> ``x.launch.xml.yaml``), and back by dropping it.

    Appending rather than replacing keeps names unique (packages do ship ``device.launch``
    beside ``device.launch.xml``) and the way back obvious. A YAML name with no XML launch
    extension left (``x.yaml``) becomes ``x.launch``.
    """
    directory, name = os.path.split(path)
    if fmt == "yaml":
        return os.path.join(directory, name + ".yaml")
    stem, _ = os.path.splitext(name)
    if not stem.lower().endswith((".launch", ".xml")):
        stem += ".launch"
    return os.path.join(directory, stem)


def convert_file(path: str, fmt: str) -> str:
    """The text of launch file ``path`` converted to ``fmt``, comments carried over
    (includes are left as written)."""
    entity = load_entity(path)
    return to_text(entity, fmt, read_comments(path, entity))


@dataclass(frozen=True)
class Converted:
    """One file written by a directory conversion."""

    source: str
    target: str


def is_launch_file(path: str, fmt_from: str) -> bool:
    """Whether ``path`` looks like a launch file of format ``fmt_from`` (cheap sniff, no parse).

    XML: ``*.launch`` and ``*.test`` (rostest) files, and any other file whose root element
    is ``<launch>`` (``*.xml``, ``*.machine``...; package.xml and URDFs are not). YAML: a
    ``*.yaml``/``*.yml`` file whose first key is ``launch:`` (rosparam files are not).
    """
    lower = path.lower()
    if fmt_from == "xml":
        if lower.endswith((".launch", ".test")):
            return True
        if format_of(path) == YAML:
            return False
        try:
            with open(path, "rb") as fh:   # iterparse left open by the early return
                if not fh.read(512).lstrip().startswith(b"<"):
                    return False
                fh.seek(0)
                for _, element in etree.iterparse(fh, events=("start",), recover=True,
                                                  resolve_entities=False, no_network=True):
                    return element.tag == "launch"
        except (etree.XMLSyntaxError, OSError):
            return False
        return False
    if format_of(path) != YAML:
        return False
    try:
        with open(path, encoding="utf-8") as fh:
            for line in fh:
                stripped = line.strip()
                if not stripped or stripped.startswith("#") or stripped == "---":
                    continue
                return stripped.startswith("launch:")
    except (OSError, UnicodeDecodeError):
        return False
    return False


def convert_tree(directory: str, fmt: str) -> list[Converted]:
    """Convert every launch file under ``directory`` to ``fmt``, writing each beside its source.

    Includes that point at a file converted in this run are rewritten to the new name (see
    ``_include_target``); others are left as written: the source files stay, and the
    interpreter reads mixed trees, so they still resolve. Every file is parsed before any is
    written, so a bad file leaves the tree untouched.
    """
    fmt_from = "xml" if fmt == "yaml" else "yaml"
    sources: list[str] = []
    for root, dirs, files in os.walk(directory):
        dirs.sort()
        for name in sorted(files):
            path = os.path.join(root, name)
            if is_launch_file(path, fmt_from):
                sources.append(os.path.abspath(path))
    converted = set(sources)
    results: list[tuple[str, str]] = []
    taken: dict[str, str] = {}
    for src in sources:
        target = target_name(src, fmt)
        if target in taken:
            raise ConvertError(f"both {taken[target]} and {src} would be converted to "
                               f"{target}", Location(src))
        taken[target] = src
        entity = load_entity(src)
        comments = read_comments(src, entity)
        _rewrite_includes(entity, src, converted, fmt)
        results.append((target, to_text(entity, fmt, comments)))
    for target, text in results:
        with open(target, "w", encoding="utf-8") as fh:
            fh.write(text)
    return [Converted(src, target) for src, (target, _) in zip(sources, results, strict=False)]


def _rewrite_includes(entity: Entity, source: str, converted: set[str], fmt: str) -> None:
    """Point ``<include file=...>`` at the converted file when it was converted too."""
    if entity.tag == "include":
        value = entity.get("file")
        if value and _include_target(value, source, converted):
            head, sep, last = value.rpartition("/")
            entity.attributes["file"] = head + sep + os.path.basename(target_name(last, fmt))
    for child in entity.children:
        _rewrite_includes(child, source, converted, fmt)


def _include_target(value: str, source: str, converted: set[str]) -> bool:
    """Whether an include ``file=`` value certainly names a file converted in this run.

    ``$(find pkg)`` (with the current package path) and ``$(dirname)`` are resolved; any
    other substitution depends on args or the environment, unknown before launch, and stands
    for "anything" (``$(find p)/launch/$(arg base)/mobile.launch.xml``). The value is
    rewritten when every existing file it could name was converted (and there is one).
    Otherwise it is left alone, which is always safe: the source it names is kept.
    """
    pattern = _static_pattern(value, source)
    if pattern is None:
        return False
    if "*" not in pattern.replace("[*]", ""):
        return os.path.normpath(value_path(pattern)) in converted
    prefix = pattern.split("*", 1)[0]
    base = prefix if prefix.endswith("/") else os.path.dirname(prefix)
    if base in ("", "/") or "[" in base:
        return False
    matches = []
    for root, _, files in os.walk(base):
        for name in files:
            path = os.path.join(root, name)
            if fnmatch.fnmatchcase(path, pattern):
                matches.append(path)
    return bool(matches) and all(path in converted for path in matches)


def value_path(pattern: str) -> str:
    """The plain path of a pattern that has no wildcard (undo ``glob.escape``)."""
    return re.sub(r"\[(.)\]", r"\1", pattern)


def _static_pattern(value: str, source: str) -> str | None:
    """``value`` as an absolute fnmatch pattern: ``$(dirname)`` and ``$(find pkg)`` resolved,
    other substitutions as ``*``; None when a package is unknown or the path is relative."""
    from orchestra.launch import substitution
    from orchestra.packages import PackageNotFound, find_package

    hole = "\0"
    try:
        bodies = substitution.collect(value)
    except OrchestraError:
        return None
    result = value
    for body in bodies:
        token = f"$({body})"
        words = body.split()
        if words == ["dirname"]:
            result = result.replace(token, os.path.dirname(source))
        elif len(words) == 2 and words[0] == "find" and "$" not in words[1]:
            try:
                result = result.replace(token, find_package(words[1]))
            except PackageNotFound:
                return None
        else:
            result = result.replace(token, hole)
    if not os.path.isabs(result):
        return None
    result = os.path.normpath(result)
    return glob.escape(result).replace(hole, "*")
