"""Finding a nodelet plugin class by its ``pkg/Type`` name, the pluginlib way.

A package declares plugins in package.xml::

    <export><nodelet plugin="${prefix}/nodelet_plugins.xml"/></export>

and the description file lists classes::

    <library path="src">
      <class name="kobuki_node/KobukiNodelet" type="kobuki_node.nodelet:KobukiNodelet"
             base_class_type="nodelet::Nodelet"/>
    </library>

For Python, ``library path`` is a directory (relative to the package) put on ``sys.path``
and ``type`` is ``module:Class`` (``module.Class`` also accepted). The package named by the
type's prefix is searched first (the common case, one file read), then every other package,
so a type exported by a differently named package still resolves, as with pluginlib.
"""
from __future__ import annotations

import importlib
import logging
import os
import sys
from dataclasses import dataclass

from lxml import etree

from orchestra.errors import Location, OrchestraError
from orchestra.packages.index import PackageNotFound, find_package, get_index

log = logging.getLogger(__name__)


class PluginError(OrchestraError):
    """A nodelet type nobody declares, or a declaration that does not load."""


@dataclass(frozen=True)
class PluginDeclaration:
    name: str            # pkg/Type
    type: str            # python module:Class
    library_dir: str     # absolute directory for sys.path
    description_file: str
    line: int


def _parse_xml(path: str) -> etree._Element:
    try:
        return etree.parse(path).getroot()
    except (OSError, etree.XMLSyntaxError) as exc:
        raise PluginError(f"cannot read plugin description: {exc}", Location(path)) from None


def plugin_files(package_dir: str) -> list[str]:
    """The nodelet plugin description files a package exports (``${prefix}`` expanded)."""
    manifest = os.path.join(package_dir, "package.xml")
    if not os.path.isfile(manifest):
        return []
    root = _parse_xml(manifest)
    files = []
    for export in root.findall("export"):
        for tag in export.findall("nodelet"):
            plugin = tag.get("plugin")
            if plugin:
                path = plugin.replace("${prefix}", package_dir)
                files.append(path if os.path.isabs(path) else os.path.join(package_dir, path))
    return files


def declarations(description_file: str, package_dir: str) -> list[PluginDeclaration]:
    """Every ``<class>`` of one plugin description file; library paths are relative to the
    exporting package, as pluginlib's are."""
    root = _parse_xml(description_file)
    libraries = [root] if root.tag == "library" else root.findall("library")
    found = []
    for library in libraries:
        library_dir = os.path.join(package_dir, library.get("path", ""))
        for cls in library.findall("class"):
            name, type_ = cls.get("name"), cls.get("type")
            if not name or not type_:
                raise PluginError("<class> needs both 'name' and 'type'",
                                  Location(description_file, cls.sourceline))
            found.append(PluginDeclaration(name, type_, library_dir, description_file,
                                           cls.sourceline or 0))
    return found


def find_declaration(type_name: str) -> PluginDeclaration:
    """The declaration of ``pkg/Type``, searching the type's own package first."""
    pkg = type_name.split("/", 1)[0]
    try:
        first = [find_package(pkg)]
    except PackageNotFound:
        first = []
    others = [d for n, d in sorted(get_index().packages.items()) if d not in first]
    for package_dir in first + others:
        try:
            found = [decl for description in plugin_files(package_dir)
                     for decl in declarations(description, package_dir)]
        except PluginError:
            if package_dir in first:
                raise  # the type's own package is broken: that is the error to report
            log.debug("skipping unreadable plugin declarations in %s", package_dir, exc_info=True)
            continue
        for decl in found:
            if decl.name == type_name:
                return decl
    raise PluginError(f"nodelet type '{type_name}' is declared by no package "
                      "(<export><nodelet plugin=.../></export> in package.xml)")


def load_class(decl: PluginDeclaration) -> type:
    """Import the class a declaration names, with its library directory on sys.path."""
    if decl.library_dir not in sys.path:
        sys.path.insert(0, decl.library_dir)
    module_name, sep, attr = decl.type.partition(":")
    if not sep:
        module_name, _, attr = decl.type.rpartition(".")
    where = Location(decl.description_file, decl.line)
    try:
        module = importlib.import_module(module_name)
    except ImportError as exc:
        raise PluginError(f"nodelet '{decl.name}': cannot import '{module_name}': {exc}",
                          where) from None
    cls = getattr(module, attr, None)
    if not isinstance(cls, type):
        raise PluginError(f"nodelet '{decl.name}': '{module_name}' has no class '{attr}'", where)
    return cls


def load_plugin(type_name: str) -> type:
    return load_class(find_declaration(type_name))
