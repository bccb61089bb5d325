"""The XML front end: a roslaunch XML file -> an ``Entity`` tree with file:line locations.

The parser is deliberately locked down (no DTD loading, no entity expansion, no network) so
that a launch file cannot read local files or reach the network through XML tricks (XXE).
Like roslaunch, the document must hold exactly one ``<launch>`` element; that element is the
root Entity. Text of an element is the concatenation of its own text pieces (what
roslaunch hands to ``<rosparam>`` as inline YAML), comments excluded.
"""
from __future__ import annotations

import bisect
import re
from collections.abc import Iterator

from lxml import etree

from orchestra.errors import Location, OrchestraError
from orchestra.launch.entity import Entity


class LaunchSyntaxError(OrchestraError):
    """The file is not well-formed XML or has no single ``<launch>`` element."""


def _parser() -> etree.XMLParser:
    return etree.XMLParser(resolve_entities=False, no_network=True, load_dtd=False,
                           dtd_validation=False, huge_tree=False, remove_pis=True,
                           remove_comments=False)


def _qualified(element: etree._Element, name: str) -> str:
    """Keep ``prefix:local`` spellings for namespaced tags and attributes (as minidom does)."""
    if not name.startswith("{"):
        return name
    qname = etree.QName(name)
    prefix = None
    for pfx, uri in (element.nsmap or {}).items():
        if uri == qname.namespace and pfx:
            prefix = pfx
            break
    return f"{prefix}:{qname.localname}" if prefix else qname.localname


# -- exact positions -----------------------------------------------------------------------
# lxml reports one line per element (where libxml2 finished reading its start tag) and no
# columns. The exact position of each start tag and attribute name is read once from the
# text, here in the front end that owns it, by a scan of the (already known well-formed)
# document: comments, CDATA, processing instructions and declarations are skipped, every
# other '<name' opens the next element in document order.

_MARKUP = re.compile(r"<(?:!--.*?-->|!\[CDATA\[.*?\]\]>|\?.*?\?>|![^>]*>|/[^>]*>|([^\s/>!?]+))",
                     re.S)
_TAG_NAME = re.compile(r"<[^\s/>]+")
_ATTRIBUTE = re.compile(r"\s+([^\s=/>]+)\s*=\s*(?:\"[^\"]*\"|'[^']*')")


class _Document:
    """The text of one document and the offset of each start tag, in document order; line
    starts and attribute offsets are computed only when a position is asked for (an error,
    ``orchestra check``): most elements of most files are never asked."""

    def __init__(self, text: str, filename: str):
        self.text = text
        self.filename = filename
        self.tags = [m.start() for m in _MARKUP.finditer(text) if m.group(1) is not None]
        self._line_starts: list[int] | None = None

    def location(self, offset: int) -> Location:
        if self._line_starts is None:
            self._line_starts = [0] + [m.end() for m in re.finditer("\n", self.text)]
        row = bisect.bisect_right(self._line_starts, offset) - 1
        return Location(self.filename, row + 1, offset - self._line_starts[row] + 1)

    def attribute_offset(self, tag_offset: int, name: str) -> int | None:
        match = _TAG_NAME.match(self.text, tag_offset)
        pos = match.end() if match else tag_offset
        while True:
            attr = _ATTRIBUTE.match(self.text, pos)
            if attr is None:
                return None
            if attr.group(1) == name:
                return attr.start(1)
            pos = attr.end()


class _ElementPositions:
    """``SourcePositions`` of one XML element."""

    __slots__ = ("_document", "_offset")

    def __init__(self, document: _Document, offset: int):
        self._document = document
        self._offset = offset

    def start(self) -> Location:
        return self._document.location(self._offset)

    def attribute(self, name: str) -> Location | None:
        offset = self._document.attribute_offset(self._offset, name)
        return self._document.location(offset) if offset is not None else None


def _decode(data: bytes) -> str:
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError:
        return data.decode("latin-1")  # positions of ASCII markup stay right


def _wrap(element: etree._Element, filename: str, document: _Document | None = None,
          offsets: Iterator[int] | None = None) -> Entity:
    positions = None
    if document is not None and offsets is not None:
        positions = _ElementPositions(document, next(offsets))
    children = []
    pieces = [element.text] if element.text else []
    for child in element:
        if isinstance(child.tag, str):
            children.append(_wrap(child, filename, document, offsets))
        if child.tail:
            pieces.append(child.tail)
    attributes = dict(element.attrib)
    if any(k[0] == "{" for k in attributes):
        attributes = {_qualified(element, k): v for k, v in attributes.items()}
    tag = element.tag
    if tag[0] == "{":
        tag = _qualified(element, tag)
    return Entity(tag=tag, attributes=attributes, children=children,
                  text="".join(pieces) or None,
                  location=Location(filename, element.sourceline), positions=positions)


def _root(tree: etree._Element, filename: str, data: bytes | None = None) -> Entity:
    elements = [el for el in tree.iter() if isinstance(el.tag, str)]
    launches = [i for i, el in enumerate(elements) if el.tag == "launch"]
    if len(launches) != 1:
        raise LaunchSyntaxError("invalid roslaunch XML: there must be exactly one <launch> "
                                f"element (found {len(launches)})", Location(filename, 1))
    document = _Document(_decode(data), filename) if data is not None else None
    if document is not None and len(document.tags) != len(elements):
        document = None  # an encoding or construct the scan does not follow: lines only
    offsets = iter(document.tags[launches[0]:]) if document is not None else None
    return _wrap(elements[launches[0]], filename, document, offsets)


def _syntax_error(exc: etree.XMLSyntaxError, filename: str) -> LaunchSyntaxError:
    line, column = getattr(exc, "position", (None, None)) or (None, None)
    if line is None:
        line = getattr(exc, "lineno", None)
    message = getattr(exc, "msg", None) or str(exc)
    return LaunchSyntaxError(f"invalid XML: {message}", Location(filename, line, column))


def parse_bytes(data: bytes, filename: str) -> Entity:
    """Parse XML bytes (encoding from the XML declaration, default UTF-8)."""
    try:
        tree = etree.fromstring(data, _parser())
    except etree.XMLSyntaxError as exc:
        raise _syntax_error(exc, filename) from None
    if tree is None:
        raise LaunchSyntaxError("invalid XML: empty document", Location(filename, 1))
    return _root(tree, filename, data)


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
