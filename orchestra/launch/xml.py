"""The XML front end: a roslaunch XML file -> an ``Entity`` tree with file:line locations.

It reads with the standard library's expat, the parser roslaunch itself reads with (through
minidom), so a document is well-formed here exactly when it is there, and names are what the
file writes (``prefix:local``, no namespace processing, as minidom gives them). expat is also
a fifth of a short ``orchestra launch --dump-params`` cheaper than lxml: the process does
not load lxml's 10 MB library (~10 ms).

The parser is locked down: a document that declares entities (``<!ENTITY>`` in a DOCTYPE) is
refused, so a launch file cannot read local files or reach the network through XML tricks
(XXE) nor blow up in memory (billion laughs); nothing else is ever loaded. Like roslaunch, the
document must hold exactly one ``<launch>`` element; that element is the root Entity. Text
of an element is the concatenation of its own text pieces (what roslaunch hands to
``<rosparam>`` as inline YAML), comments excluded.
"""
from __future__ import annotations

import bisect
import re
from xml.parsers import expat

from orchestra.errors import Location, OrchestraError, offset_location
from orchestra.launch.entity import Entity


class LaunchSyntaxError(OrchestraError):
    """The file is not well-formed XML or has no single ``<launch>`` element."""


# Elements nested deeper than this are refused (the bound libxml2 has by default, kept when
# the front end moved to expat, which has none): everything after the parse walks the tree
# recursively, and a file must not be able to exhaust the stack (docs/compat.md).
MAX_DEPTH = 256


# -- exact positions -----------------------------------------------------------------------
# Each element keeps the line its start tag begins on (expat's, for free) and no column.
# The exact position of each start tag and attribute name is read once from the text, here
# in the front end that owns it, by a scan of the (already known well-formed) document:
# comments, CDATA, processing instructions and declarations are skipped, every other
# '<name' opens the next element in document order.

_MARKUP = re.compile(r"<(?:!--.*?-->|!\[CDATA\[.*?\]\]>|\?.*?\?>|![^>]*>|/[^>]*>|([^\s/>!?]+))",
                     re.S)
_TAG_NAME = re.compile(r"<[^\s/>]+")
_ATTRIBUTE = re.compile(r"\s+([^\s=/>]+)\s*=\s*(?:\"[^\"]*\"|'[^']*')")


class _Document:
    """``SourcePositions`` of every element of one document: the text and, once a position
    is asked for (an error, ``orchestra check``), the offset of each start tag in document
    order and the line starts. Most elements of most files are never asked, so a load
    neither scans the text nor keeps an object per element: only each element's index."""

    def __init__(self, data: bytes, filename: str, elements: int):
        self.data = data
        self.filename = filename
        self.elements = elements  # element count the parser saw: the scan must find as many
        # id(entity) -> its index in document order. Ids, not the entities: each entity
        # holds this document, and a list of them here would make every tree a reference
        # cycle, freed only by the cyclic collector (3.5 ms of the corpus, 20-80 ms a big tree)
        self.index_of: dict[int, int] = {}
        self._text: str | None = None
        self._tags: list[int] | None = None
        self._line_starts: list[int] | None = None

    def start(self, entity: Entity) -> Location:
        offset = self._offset(entity)
        return entity.location if offset is None else self._location(offset)

    def attribute(self, entity: Entity, name: str) -> Location | None:
        tag_offset = self._offset(entity)
        if tag_offset is None:
            return None
        offset = self._attribute_offset(tag_offset, name)
        return self._location(offset) if offset is not None else None

    def _offset(self, entity: Entity) -> int | None:
        """Where ``entity``'s start tag is; None when the scan does not see the elements
        the parser saw (an encoding or construct it does not follow: the element's line
        stands)."""
        index = self.index_of.get(id(entity))
        tags = self._scan()
        return tags[index] if index is not None and tags is not None else None

    def _scan(self) -> list[int] | None:
        if self._tags is None:
            self._text = _decode(self.data)
            self._tags = [m.start() for m in _MARKUP.finditer(self._text)
                          if m.group(1) is not None]
        return self._tags if len(self._tags) == self.elements else None

    def _location(self, offset: int) -> Location:
        assert self._text is not None  # offsets come from _scan()
        if self._line_starts is None:
            self._line_starts = [0] + [m.end() for m in re.finditer("\n", self._text)]
        row = bisect.bisect_right(self._line_starts, offset) - 1
        return Location(self.filename, row + 1, offset - self._line_starts[row] + 1)

    def _attribute_offset(self, tag_offset: int, name: str) -> int | None:
        assert self._text is not None
        match = _TAG_NAME.match(self._text, tag_offset)
        pos = match.end() if match else tag_offset
        while True:
            attr = _ATTRIBUTE.match(self._text, pos)
            if attr is None:
                return None
            if attr.group(1) == name:
                return attr.start(1)
            pos = attr.end()


def _decode(data: bytes) -> str:
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError:
        return data.decode("latin-1")  # positions of ASCII markup stay right


class _Refused(Exception):
    """Raised from an expat handler to stop the parse at something this front end refuses
    (see the module): an entity declaration, a reference to an entity it was not given,
    nesting deeper than MAX_DEPTH. ``offset`` is the byte offset expat was at."""

    def __init__(self, message: str, offset: int):
        super().__init__(message)
        self.message = message
        self.offset = offset


def _read(data: bytes, filename: str, document: _Document) -> tuple[list[Entity], list[int]]:
    """Every element of ``data`` as an Entity (children linked), in document order, and the
    indexes of the ``<launch>`` elements among them. One pass of expat's events: an Entity
    is made when its start tag is read; text goes to the innermost open one."""
    parser = expat.ParserCreate()
    parser.buffer_text = True  # one text event between two tags, not one per line
    entities: list[Entity] = []
    launches: list[int] = []
    open_entities: list[Entity] = []
    namespaced = b"xmlns" in data  # declarations are attributes to expat, not to roslaunch

    def start(tag: str, attributes: dict[str, str]) -> None:
        if len(open_entities) == MAX_DEPTH:
            raise _Refused(f"elements nested more than {MAX_DEPTH} deep",
                           parser.CurrentByteIndex)
        if namespaced:
            attributes = {k: v for k, v in attributes.items()
                          if k != "xmlns" and not k.startswith("xmlns:")}
        made = Entity(tag, attributes, [], None, Location(filename, parser.CurrentLineNumber),
                      document)
        if tag == "launch":
            launches.append(len(entities))
        entities.append(made)
        if open_entities:
            open_entities[-1].children.append(made)
        open_entities.append(made)

    def end(tag: str) -> None:
        open_entities.pop()

    def text(data: str) -> None:
        if open_entities:  # text outside the root element is whitespace: not the tree's
            innermost = open_entities[-1]
            before = innermost.text
            innermost.text = data if before is None else before + data

    def entity_declared(*_: object) -> None:
        declared = data.rfind(b"<!ENTITY", 0, parser.CurrentByteIndex + 1)
        raise _Refused("entity declarations (<!ENTITY>) are not allowed in launch files: use "
                       "<arg> for values to reuse",
                       declared if declared >= 0 else parser.CurrentByteIndex)

    def entity_skipped(name: str, is_parameter_entity: bool) -> None:
        # expat skips (rather than refuses) an entity it has no declaration of when the
        # document names an external DTD, which is never read here
        raise _Refused(f"undefined entity &{name};", parser.CurrentByteIndex)

    parser.StartElementHandler = start
    parser.EndElementHandler = end
    parser.CharacterDataHandler = text
    parser.EntityDeclHandler = entity_declared
    parser.SkippedEntityHandler = entity_skipped
    try:
        parser.Parse(data, True)
    finally:  # the handlers and the parser refer to each other: no cycle left behind
        parser.StartElementHandler = parser.EndElementHandler = None
        parser.CharacterDataHandler = parser.EntityDeclHandler = None
        parser.SkippedEntityHandler = None
    return entities, launches


def _launch_count_error(found: int, filename: str) -> LaunchSyntaxError:
    return LaunchSyntaxError("invalid roslaunch XML: there must be exactly one <launch> "
                             f"element (found {found})", Location(filename, 1))


def parse_bytes(data: bytes, filename: str) -> Entity:
    """Parse XML bytes (encoding from the XML declaration, default UTF-8)."""
    document = _Document(data, filename, 0)
    try:
        entities, launches = _read(data, filename, document)
    except expat.ExpatError as exc:
        message = expat.ErrorString(exc.code) if exc.code else str(exc)
        raise LaunchSyntaxError(f"invalid XML: {message}",
                                Location(filename, exc.lineno, exc.offset + 1)) from None
    except _Refused as exc:
        raise LaunchSyntaxError(f"invalid XML: {exc.message}",
                                offset_location(filename, data, exc.offset)) from None
    except (LookupError, ValueError) as exc:  # the XML declaration names an encoding expat
        raise LaunchSyntaxError(                # cannot read (unknown, or multi-byte)
            f"invalid XML: the declared encoding cannot be read: {exc}",
            Location(filename, 1)) from None
    if len(launches) != 1:
        raise _launch_count_error(len(launches), filename)
    document.elements = len(entities)
    document.index_of = {id(entity): index for index, entity in enumerate(entities)}
    return entities[launches[0]]


def parse_string(text: str, filename: str = "<string>") -> Entity:
    """Parse launch XML held in a string; ``filename`` is only used in locations."""
    return parse_bytes(text.encode("utf-8") if isinstance(text, str) else text, filename)


def parse_file(path: str) -> Entity:
    """Parse a launch XML file; a missing or unreadable file is a user error, not a crash."""
    from orchestra.launch.files import read_bytes
    try:
        data = read_bytes(path)
    except OSError as exc:
        raise LaunchSyntaxError(f"cannot read launch file: {exc.strerror}",
                                Location(path)) from None
    return parse_bytes(data, path)
