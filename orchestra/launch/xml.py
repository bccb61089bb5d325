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

from lxml import etree

from orchestra.errors import Location, OrchestraError
from orchestra.launch.entity import Entity


class LaunchSyntaxError(OrchestraError):
    """The file is not well-formed XML or has no single ``<launch>`` element."""


def _parser() -> etree.XMLParser:
    # comments are dropped while parsing (libxml2 joins the text around one, which is the
    # element text this front end gives); ``orchestra convert`` reads them with its own
    return etree.XMLParser(resolve_entities=False, no_network=True, load_dtd=False,
                           dtd_validation=False, huge_tree=False, remove_pis=True,
                           remove_comments=True)


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
    """``SourcePositions`` of every element of one document: the text and, once a position
    is asked for (an error, ``orchestra check``), the offset of each start tag in document
    order and the line starts. Most elements of most files are never asked, so a load
    neither scans the text nor keeps an object per element: only each element's index."""

    def __init__(self, data: bytes, filename: str, elements: int):
        self.data = data
        self.filename = filename
        self.elements = elements  # element count lxml saw: the scan must find as many
        self.index_of: dict[int, int] = {}  # id(entity) -> its index in document order
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
        lxml saw (an encoding or construct it does not follow: lxml's line stands)."""
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


def _prefixes_possible(data: bytes | None) -> bool:
    """Whether an attribute of the document may have a namespace prefix (``a:b``): only
    prefixed attribute names are in a namespace (a default ``xmlns`` applies to tags, which
    say so themselves), and names are written literally, so in an ASCII-compatible
    encoding a document without a ``:`` byte has none. Others (UTF-16/32, EBCDIC): maybe."""
    if data is None:
        return True
    head = data[3:64] if data.startswith(b"\xef\xbb\xbf") else data[:64]
    head = head.lstrip(b" \t\r\n")
    return b":" in data or head[:1] != b"<" or head[1:2] == b"\x00"


def _entities(start: etree._Element, filename: str, document: _Document | None,
              prefixes: bool, first_index: int) -> tuple[Entity, int, int]:
    """The Entity of ``start`` and its subtree, in one pass over the elements in document
    order; and how many elements and ``<launch>`` elements were seen.

    Each element's attributes, text pieces and line are read once (lxml's property access
    is most of the cost); positions are only recorded as the element's index in the
    document, resolved by ``_Document`` when asked for."""
    count = first_index   # the index of the next element
    launches = 0
    index_of = document.index_of if document is not None else None

    def entity(element: etree._Element) -> Entity:
        nonlocal count, launches
        index = count
        count = index + 1
        tag = element.tag
        if tag == "launch":
            launches += 1
        elif tag[0] == "{":
            tag = _qualified(element, tag)
        children = []
        text = element.text
        if len(element):  # most elements are leaves: no iterator for them
            pieces = None
            for child in element:
                if child.tag.__class__ is str:
                    children.append(entity(child))
                tail = child.tail
                if tail:
                    if pieces is None:
                        pieces = [text] if text else []
                    pieces.append(tail)
            if pieces is not None:
                text = "".join(pieces)
        attributes = dict(element.items())
        if prefixes:
            for name in attributes:
                if name[0] == "{":
                    attributes = {_qualified(element, k): v for k, v in attributes.items()}
                    break
        made = Entity(tag, attributes, children, text or None,
                      Location(filename, element.sourceline), document)
        if index_of is not None:
            index_of[id(made)] = index
        return made

    root = entity(start)
    return root, count - first_index, launches


def _root(tree: etree._Element, filename: str, data: bytes | None = None) -> Entity:
    prefixes = _prefixes_possible(data)
    if tree.tag == "launch":
        # the usual document: the walk from the root sees every element
        start, first, elements = tree, 0, None
    else:
        found = [el for el in tree.iter() if isinstance(el.tag, str)]
        launches = [i for i, el in enumerate(found) if el.tag == "launch"]
        if len(launches) != 1:
            raise _launch_count_error(len(launches), filename)
        start, first, elements = found[launches[0]], launches[0], len(found)
    document = _Document(data, filename, elements or 0) if data is not None else None
    root, seen, launch_count = _entities(start, filename, document, prefixes, first)
    if launch_count != 1:
        raise _launch_count_error(launch_count, filename)
    if document is not None and elements is None:
        document.elements = seen
    return root


def _launch_count_error(found: int, filename: str) -> LaunchSyntaxError:
    return LaunchSyntaxError("invalid roslaunch XML: there must be exactly one <launch> "
                             f"element (found {found})", Location(filename, 1))


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
