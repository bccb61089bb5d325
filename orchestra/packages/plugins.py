"""Export lookup across packages: ``rospack plugins --attrib=ATTR TOOL``.

pluginlib-style tools (nodelet, rviz, controller managers) find their plugins through the
``<export><TOOL ATTR="..."/></export>`` entries of packages that depend on TOOL. Each manifest
is first scanned as bytes for ``<TOOL`` so only the few packages that can match are parsed;
``${prefix}`` in a value becomes the exporting package's directory, as rospack does.
"""
from __future__ import annotations

import os
from dataclasses import dataclass

from orchestra.log_setup import logger
from orchestra.packages.index import PackageIndex, get_index
from orchestra.packages.manifest import InvalidManifest, parse_manifest

log = logger(__name__)


@dataclass(frozen=True)
class PluginExport:
    package: str
    directory: str
    value: str


def _mentions(directory: str, tool: str) -> bool:
    try:
        with open(os.path.join(directory, "package.xml"), "rb") as fh:
            return f"<{tool}".encode() in fh.read()
    except OSError:
        return False


def find_plugins(tool: str, attrib: str = "plugin", index: PackageIndex | None = None,
                 strict: bool = False) -> list[PluginExport]:
    """Every ``<tool attrib=...>`` export of TOOL itself and of the packages depending on it.

    A broken manifest elsewhere on the path is skipped with a debug log (one bad checkout
    must not hide every plugin), unless ``strict``.
    """
    index = get_index() if index is None else index
    found: list[PluginExport] = []
    for name in index.names():
        directory = index.packages[name]
        if not _mentions(directory, tool):
            continue
        try:
            manifest = parse_manifest(directory)
        except InvalidManifest:
            if strict:
                raise
            log.debug("skipping %s: invalid manifest", directory, exc_info=True)
            continue
        if name != tool and tool not in manifest.depends():
            continue
        for export in manifest.exports:
            value = dict(export.attributes).get(attrib)
            if export.tag == tool and value is not None:
                found.append(PluginExport(name, directory, value.replace("${prefix}", directory)))
    return found
