"""The YAML document ``roslaunch --dump-params`` prints: every parameter of a launch.

Scripts diff it against roslaunch's, so it is PyYAML's ``safe_dump`` byte for byte. Its own
module (not rosparam's ``dump``) because ``orchestra launch --dump-params`` is a start-up-time
path: it imports nothing of the XML-RPC client, and a document whose names and values are all
plain (names, paths, words, numbers, booleans, lists of them: most launches) is written here
without importing yaml at all (a sixth of a one-node ``--dump-params``). Every other document
is PyYAML's (``dump_launch_yaml.py``); tests/test_params_yaml.py checks both against
``yaml.dump``.
"""
from __future__ import annotations

import math
import re
from typing import Any

#: text PyYAML writes as it is (a plain scalar): names, paths and words of these characters,
#: unless YAML 1.1 reads it as something else than text (the words below; the leading
#: character rules out numbers, dates, ``~``, ``.inf``, ``<<`` and indicators)
_PLAIN_TEXT = re.compile(r"[A-Za-z_/][A-Za-z0-9_./-]*(?: [A-Za-z0-9_./-]+)*\Z")
_NOT_TEXT = frozenset(("yes", "Yes", "YES", "no", "No", "NO", "true", "True", "TRUE", "false",
                       "False", "FALSE", "on", "On", "ON", "off", "Off", "OFF", "null", "Null",
                       "NULL"))
#: PyYAML folds plain text at a space past this column
_WIDTH = 80
#: PyYAML writes a longer key as ``? key`` (it counts the key's 5-character ``!!str`` tag into
#: its 128-character limit of a simple key)
_SIMPLE_KEY_MAX = 122


def _plain_scalar(value: Any, before: int) -> str | None:
    """``value`` as PyYAML's safe dumper writes it after ``before`` characters of its line,
    when that is one plain or empty scalar of the kinds above (text, exact ints, floats,
    booleans, None); None for anything else."""
    kind = type(value)
    if kind is str:
        if not value:
            return "''"
        if (_PLAIN_TEXT.match(value) is None or value in _NOT_TEXT
                or (" " in value and before + len(value) > _WIDTH)):
            return None
        return value
    if kind is bool:
        return "true" if value else "false"
    if kind is int:
        return str(value)
    if kind is float:
        if value != value:
            return ".nan"
        if math.isinf(value):
            return ".inf" if value > 0 else "-.inf"
        text = repr(value).lower()
        # 1e+17 is no YAML 1.1 float; PyYAML writes it 1.0e+17
        return text.replace("e", ".0e", 1) if "." not in text and "e" in text else text
    if value is None:
        return "null"
    return None


def _entry(key: Any, value: Any) -> str | None:
    """The lines of ``key: value`` in PyYAML's block document, when both are plain (a list
    of plain scalars is a block sequence under the key); None otherwise."""
    if (type(key) is not str or len(key) > _SIMPLE_KEY_MAX or " " in key
            or _plain_scalar(key, 0) != key):
        return None
    if type(value) is list:
        if not value:
            return f"{key}: []\n"
        items = [_plain_scalar(item, 2) for item in value]
        if None in items:
            return None
        return f"{key}:\n" + "".join(f"- {item}\n" for item in items)
    text = _plain_scalar(value, len(key) + 2)
    return None if text is None else f"{key}: {text}\n"


def plain_document(params: dict[str, Any]) -> str | None:
    """PyYAML's block document of ``params`` when every entry is plain (see ``_entry``), in
    key order; None otherwise."""
    if not params:
        return "{}\n"
    lines = []
    for key in sorted(params):
        entry = _entry(key, params[key])
        if entry is None:
            return None
        lines.append(entry)
    return "".join(lines)


def dump_launch_params(params: dict[str, Any]) -> str:
    """The YAML document ``roslaunch --dump-params`` prints for ``params`` (PyYAML's
    safe_dump: block style, sorted keys, ASCII escapes)."""
    text = plain_document(params)
    if text is None:
        from orchestra.params.dump_launch_yaml import yaml_document

        text = yaml_document(params)
    return text
