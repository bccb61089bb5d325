"""package.xml (formats 1, 2 and 3, REP 127/140/149) and legacy rosbuild manifest.xml.

The crawl only needs a package's name; the rest of the manifest (dependencies for
``pkg deps``, exports, people) is parsed on demand here, with lxml's safe settings (no entity
expansion, no DTD or network access) because manifests come from any checkout on the path.
Every problem raises ``InvalidManifest`` naming the file and line.

Dependencies keep the tag they were declared with (``declared``) and are also expanded to the
effective kinds the format defines: ``<depend>`` means build + build_export + exec, and format
1's ``<run_depend>`` means build_export + exec.
"""
from __future__ import annotations

import os
import re
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Literal, overload

from lxml import etree

from orchestra.errors import Location, OrchestraError

#: effective dependency kinds, in the order they are reported
KINDS = ("buildtool", "buildtool_export", "build", "build_export", "exec", "test", "doc")

#: declared tag -> effective kinds, per format
_FORMAT1_TAGS = {
    "buildtool_depend": ("buildtool",),
    "build_depend": ("build",),
    "run_depend": ("build_export", "exec"),
    "test_depend": ("test",),
}
_FORMAT2_TAGS = {
    "depend": ("build", "build_export", "exec"),
    "buildtool_depend": ("buildtool",),
    "buildtool_export_depend": ("buildtool_export",),
    "build_depend": ("build",),
    "build_export_depend": ("build_export",),
    "exec_depend": ("exec",),
    "test_depend": ("test",),
    "doc_depend": ("doc",),
}
#: tags that name other packages but are not dependencies
_RELATION_TAGS = ("conflict", "replace", "group_depend", "member_of_group")
_VERSION_ATTRS = ("version_lt", "version_lte", "version_eq", "version_gte", "version_gt")
_VERSION = re.compile(r"^\d+\.\d+\.\d+$")

#: what a sourced ROS 1 (noetic) environment defines; conditions see these unless the
#: environment says otherwise, so `$ROS_VERSION == 1` holds without ROS installed
CONDITION_DEFAULTS = {"ROS_VERSION": "1", "ROS_PYTHON_VERSION": "3", "ROS_DISTRO": "noetic"}

_PARSER = etree.XMLParser(resolve_entities=False, no_network=True, load_dtd=False,
                          huge_tree=False, remove_comments=True, remove_pis=True)


class InvalidManifest(OrchestraError):
    """A package.xml or manifest.xml that cannot be understood."""


@dataclass(frozen=True)
class Person:
    name: str
    email: str | None = None


@dataclass(frozen=True)
class Dependency:
    """One declared dependency tag."""

    name: str
    tag: str  # as written: depend, build_depend, run_depend, exec_depend, ...
    versions: tuple[tuple[str, str], ...] = ()  # (("version_gte", "1.2.0"),)
    condition: str | None = None
    line: int | None = None


@dataclass(frozen=True)
class Export:
    """One child of ``<export>``: its tag, attributes and inner content (text/XML)."""

    tag: str
    attributes: tuple[tuple[str, str], ...] = ()
    content: str = ""


@dataclass(frozen=True)
class Manifest:
    """Everything a package's manifest says."""

    path: str
    format: int  # 1, 2, 3; 0 for a rosbuild manifest.xml
    name: str
    version: str | None
    description: str
    maintainers: tuple[Person, ...] = ()
    authors: tuple[Person, ...] = ()
    licenses: tuple[str, ...] = ()
    urls: tuple[tuple[str | None, str], ...] = ()
    declared: tuple[Dependency, ...] = ()
    relations: tuple[Dependency, ...] = ()  # conflict, replace, group_depend, member_of_group
    exports: tuple[Export, ...] = ()
    warnings: tuple[str, ...] = field(default=(), compare=False)

    def depends(self, kinds: tuple[str, ...] | None = None,
                environ: Mapping[str, str] | None = None) -> list[str]:
        """Names this package depends on with any of ``kinds`` (default all), conditions applied.

        ``environ`` defaults to the process environment over ``CONDITION_DEFAULTS``.
        """
        if environ is None:
            environ = {**CONDITION_DEFAULTS, **os.environ}
        wanted = set(KINDS if kinds is None else kinds)
        table = _FORMAT1_TAGS if self.format == 1 else _FORMAT2_TAGS
        names: list[str] = []
        for dep in self.declared:
            effective = ("build", "build_export", "exec") if self.format == 0 else table[dep.tag]
            if wanted.intersection(effective) and dep.name not in names:
                if dep.condition is None or evaluate_condition(dep.condition, environ, self.path, dep.line):
                    names.append(dep.name)
        return names

    def dependencies_by_kind(self) -> dict[str, list[str]]:
        """Effective kind -> sorted names, the shape catkin_pkg's Package attributes have."""
        return {kind: sorted(self.depends((kind,))) for kind in KINDS}

    def relation(self, tag: str) -> list[str]:
        return [dep.name for dep in self.relations if dep.tag == tag]

    @property
    def is_metapackage(self) -> bool:
        return any(export.tag == "metapackage" for export in self.exports)

    @property
    def build_type(self) -> str:
        for export in self.exports:
            if export.tag == "build_type":
                return export.content.strip() or "catkin"
        return "catkin"


# -- conditions (REP 149) --------------------------------------------------------------------

_TOKEN = re.compile(r"\s*(?:(\$[A-Za-z_][A-Za-z0-9_]*)|(==|!=|>=|<=|<|>)|(\(|\))|"
                    r"([A-Za-z0-9_.\-]+)|\"([^\"]*)\"|'([^']*)')")


def evaluate_condition(text: str, environ: Mapping[str, str] | None = None,
                       path: str = "<condition>", line: int | None = None) -> bool:
    """Evaluate a REP 149 ``condition`` (``$ROS_VERSION == 1 and $X != ''``) against ``environ``.

    Unset variables are the empty string, as in catkin_pkg. Only comparisons, ``and``, ``or``
    and parentheses exist; anything else is an error naming the manifest.
    """
    env = os.environ if environ is None else environ
    tokens: list[tuple[str, str]] = []
    pos = 0
    text_stripped = text.strip()
    while pos < len(text_stripped):
        match = _TOKEN.match(text_stripped, pos)
        if match is None or match.end() == pos:
            raise InvalidManifest(f"invalid condition {text!r}", Location(path, line))
        var, op, paren, word, dq, sq = match.groups()
        if var:
            tokens.append(("value", env.get(var[1:], "")))
        elif op:
            tokens.append(("op", op))
        elif paren:
            tokens.append((paren, paren))
        elif word in ("and", "or"):
            tokens.append((word, word))
        elif word is not None:
            tokens.append(("value", word))
        else:
            tokens.append(("value", dq if dq is not None else sq))
        pos = match.end()

    position = 0

    def fail() -> InvalidManifest:
        return InvalidManifest(f"invalid condition {text!r}", Location(path, line))

    def peek() -> str | None:
        return tokens[position][0] if position < len(tokens) else None

    def take() -> tuple[str, str]:
        nonlocal position
        if position >= len(tokens):
            raise fail()
        position += 1
        return tokens[position - 1]

    def comparison() -> bool:
        if peek() == "(":
            take()
            value = disjunction()
            if take()[0] != ")":
                raise fail()
            return value
        kind, left = take()
        kind2, op = take()
        kind3, right = take()
        if kind != "value" or kind2 != "op" or kind3 != "value":
            raise fail()
        return {"==": left == right, "!=": left != right, ">=": left >= right,
                "<=": left <= right, "<": left < right, ">": left > right}[op]

    def conjunction() -> bool:
        value = comparison()
        while peek() == "and":
            take()
            value = comparison() and value
        return value

    def disjunction() -> bool:
        value = conjunction()
        while peek() == "or":
            take()
            value = conjunction() or value
        return value

    result = disjunction()
    if position != len(tokens):
        raise fail()
    return result


# -- parsing ------------------------------------------------------------------------------------

def _text(element) -> str:
    return "".join(element.itertext()).strip()


def _inner_xml(element) -> str:
    parts = [element.text or ""]
    for child in element:
        parts.append(etree.tostring(child, encoding="unicode", with_tail=True))
    return "".join(parts).strip()


def _person(element) -> Person:
    email = element.get("email")
    return Person(" ".join(_text(element).split()), email.strip() if email else None)


@overload
def _single(root, tag: str, path: str, required: Literal[True]) -> etree._Element: ...
@overload
def _single(root, tag: str, path: str, required: bool) -> etree._Element | None: ...


def _single(root, tag: str, path: str, required: bool) -> etree._Element | None:
    found = root.findall(tag)
    if len(found) > 1:
        raise InvalidManifest(f"<{tag}> may appear only once", Location(path, found[1].sourceline))
    if not found:
        if required:
            raise InvalidManifest(f"missing required <{tag}>", Location(path, root.sourceline))
        return None
    return found[0]


def _read(path: str):
    try:
        with open(path, "rb") as fh:
            data = fh.read()
    except OSError as exc:
        raise InvalidManifest(f"cannot read manifest: {exc.strerror}", Location(path)) from None
    try:
        return etree.fromstring(data, _PARSER, base_url=path)
    except etree.XMLSyntaxError as exc:
        line = exc.position[0] if exc.position else exc.lineno
        column = exc.position[1] if exc.position else None
        message = exc.msg or str(exc)
        message = re.sub(r",?\s*line \d+, column \d+$", "", message)
        raise InvalidManifest(f"invalid XML: {message}", Location(path, line, column)) from None


def parse_manifest(path: str) -> Manifest:
    """Parse ``path`` (a package.xml or manifest.xml file, or a package directory)."""
    if os.path.isdir(path):
        for name in ("package.xml", "manifest.xml"):
            if os.path.isfile(os.path.join(path, name)):
                path = os.path.join(path, name)
                break
        else:
            raise InvalidManifest("no package.xml or manifest.xml in this directory", Location(path))
    root = _read(path)
    if os.path.basename(path) == "manifest.xml":
        return _parse_rosbuild(root, path)
    return _parse_package_xml(root, path)


def _parse_package_xml(root, path: str) -> Manifest:
    if root.tag != "package":
        raise InvalidManifest(f"the root element must be <package>, not <{root.tag}>",
                              Location(path, root.sourceline))
    raw_format = root.get("format", "1").strip()
    if raw_format not in ("1", "2", "3"):
        raise InvalidManifest(f"unsupported package format {raw_format!r} (1, 2 or 3 expected)",
                              Location(path, root.sourceline))
    fmt = int(raw_format)
    warnings: list[str] = []

    name_el = _single(root, "name", path, required=True)
    name = _text(name_el)
    if not name:
        raise InvalidManifest("<name> is empty", Location(path, name_el.sourceline))
    version_el = _single(root, "version", path, required=True)
    version = _text(version_el)
    if not _VERSION.match(version):
        raise InvalidManifest(f"version {version!r} is not MAJOR.MINOR.PATCH",
                              Location(path, version_el.sourceline))
    description_el = _single(root, "description", path, required=False)
    description = " ".join(_text(description_el).split()) if description_el is not None else ""
    if not description:
        warnings.append("missing or empty <description>")

    maintainers = tuple(_person(el) for el in root.findall("maintainer"))
    if not maintainers:
        warnings.append("no <maintainer>")
    authors = tuple(_person(el) for el in root.findall("author"))
    licenses = tuple(_text(el) for el in root.findall("license"))
    if not licenses:
        warnings.append("no <license>")
    urls = tuple((el.get("type"), _text(el)) for el in root.findall("url"))

    tags = _FORMAT1_TAGS if fmt == 1 else _FORMAT2_TAGS
    relation_tags = _RELATION_TAGS if fmt == 3 else ("conflict", "replace")
    known = {"name", "version", "description", "maintainer", "author", "license", "url",
             "export", *tags, *relation_tags}
    declared: list[Dependency] = []
    relations: list[Dependency] = []
    for child in root:
        if not isinstance(child.tag, str):
            continue
        if child.tag not in known:
            raise InvalidManifest(f"unknown tag <{child.tag}> in a format {fmt} package.xml",
                                  Location(path, child.sourceline))
        if child.tag in tags or child.tag in relation_tags:
            dep_name = _text(child)
            if not dep_name:
                raise InvalidManifest(f"<{child.tag}> is empty", Location(path, child.sourceline))
            condition = child.get("condition") if fmt == 3 else None
            versions = tuple((a, child.get(a)) for a in _VERSION_ATTRS if child.get(a) is not None)
            dep = Dependency(dep_name, child.tag, versions, condition, child.sourceline)
            (declared if child.tag in tags else relations).append(dep)
            if dep_name == name and child.tag in tags:
                raise InvalidManifest(f"package '{name}' must not depend on itself",
                                      Location(path, child.sourceline))

    exports: list[Export] = []
    export_el = _single(root, "export", path, required=False)
    if export_el is not None:
        for child in export_el:
            if isinstance(child.tag, str):
                exports.append(Export(child.tag, tuple(sorted(child.attrib.items())),
                                      _inner_xml(child)))
    return Manifest(path=path, format=fmt, name=name, version=version, description=description,
                    maintainers=maintainers, authors=authors, licenses=licenses, urls=urls,
                    declared=tuple(declared), relations=tuple(relations),
                    exports=tuple(exports), warnings=tuple(warnings))


def _parse_rosbuild(root, path: str) -> Manifest:
    """A rosbuild manifest.xml: the name is the directory's, dependencies are ``<depend package>``."""
    if root.tag != "package":
        raise InvalidManifest(f"the root element must be <package>, not <{root.tag}>",
                              Location(path, root.sourceline))
    declared = []
    for el in root.findall("depend"):
        package = el.get("package")
        if not package:
            raise InvalidManifest("<depend> needs a package attribute", Location(path, el.sourceline))
        declared.append(Dependency(package, "depend", line=el.sourceline))
    description_el = root.find("description")
    authors = tuple(Person(a.strip()) for el in root.findall("author")
                    for a in _text(el).split(",") if a.strip())
    exports = []
    export_el = root.find("export")
    if export_el is not None:
        exports = [Export(c.tag, tuple(sorted(c.attrib.items())), _inner_xml(c))
                   for c in export_el if isinstance(c.tag, str)]
    return Manifest(path=path, format=0, name=os.path.basename(os.path.dirname(os.path.abspath(path))),
                    version=None,
                    description=" ".join(_text(description_el).split()) if description_el is not None else "",
                    authors=authors, licenses=tuple(_text(el) for el in root.findall("license")),
                    declared=tuple(declared), exports=tuple(exports))
