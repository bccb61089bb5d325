"""The launch front ends, and the one place that picks which reads a file.

A front end turns file text into the ``Entity`` tree the interpreter reads. There are two,
XML (roslaunch's own) and YAML (the same language without angle brackets); which one reads
a file depends only on its name: ``*.yaml``/``*.yml`` (``x.launch.yaml``) is YAML,
everything else is XML, as roslaunch reads any file given to it as XML. The interpreter,
``orchestra check``, ``orchestra convert`` and the CLI all ask here, so they cannot disagree
about a file.

The front-end modules are imported when first used: a run of XML files never loads the YAML
reader's code and the other way round.
"""
from __future__ import annotations

import os
from collections.abc import Callable
from typing import NamedTuple

from orchestra.launch.entity import Entity

XML = "xml"
YAML = "yaml"
FORMATS = (XML, YAML)
YAML_EXTENSIONS = (".yaml", ".yml")


class Frontend(NamedTuple):
    """One front end: its format name and how it reads a file or a string. (A NamedTuple:
    every launch process builds this class, and a frozen dataclass's generated methods cost
    ~3x as much to create, ~5 M instructions.)"""

    name: str
    parse_file: Callable[[str], Entity]
    parse_string: Callable[[str, str], Entity]


def _xml() -> Frontend:
    from orchestra.launch import xml
    return Frontend(XML, xml.parse_file, xml.parse_string)


def _yaml() -> Frontend:
    from orchestra.launch import yaml
    return Frontend(YAML, yaml.parse_file, yaml.parse_string)


_LOADERS: dict[str, Callable[[], Frontend]] = {XML: _xml, YAML: _yaml}
_LOADED: dict[str, Frontend] = {}


def format_of(path: str) -> str:
    """``"yaml"`` or ``"xml"``: the format a launch file is read as, by its name."""
    return YAML if os.path.splitext(path)[1].lower() in YAML_EXTENSIONS else XML


def frontend(name: str) -> Frontend:
    """The front end of format ``name`` (``"xml"`` or ``"yaml"``)."""
    found = _LOADED.get(name)
    if found is None:
        found = _LOADED[name] = _LOADERS[name]()
    return found


def parse_file(path: str) -> Entity:
    """The root Entity of the launch file at ``path``, read by the front end for its name."""
    return frontend(format_of(path)).parse_file(path)


def parse_string(text: str, filename: str, fmt: str = XML) -> Entity:
    """The root Entity of launch text in format ``fmt``; ``filename`` names it in errors."""
    return frontend(fmt).parse_string(text, filename)
