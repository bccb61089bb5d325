"""The XML front end: a roslaunch XML file -> an ``Entity`` tree with file:line locations.

The parser is deliberately locked down (no DTD loading, no entity expansion, no network) so
that a launch file cannot read local files or reach the network through XML tricks (XXE).
Like roslaunch, the document must hold exactly one ``<launch>`` element; that element is the
root Entity. Text of an element is the concatenation of its own text pieces (what
roslaunch hands to ``<rosparam>`` as inline YAML), comments excluded.
"""
from __future__ import annotations

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


def _wrap(element: etree._Element, filename: str) -> Entity:
    children = []
    pieces = [element.text] if element.text else []
    for child in element:
        if isinstance(child.tag, str):
            children.append(_wrap(child, filename))
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
                  location=Location(filename, element.sourceline))


def _root(tree: etree._Element, filename: str) -> Entity:
    launches = [el for el in tree.iter() if isinstance(el.tag, str) and el.tag == "launch"]
    if len(launches) != 1:
        raise LaunchSyntaxError("invalid roslaunch XML: there must be exactly one <launch> "
                                f"element (found {len(launches)})", Location(filename, 1))
    return _wrap(launches[0], filename)


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
    return _root(tree, filename)


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
