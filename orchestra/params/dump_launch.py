"""The YAML document ``roslaunch --dump-params`` prints: every parameter of a launch.

Scripts diff it against roslaunch's, so it is PyYAML's ``safe_dump`` byte for byte. Its own
module (not rosparam's ``dump``) because ``orchestra launch --dump-params`` is a start-up-time
path: it imports nothing of the XML-RPC client, and a document whose names and values are all
plain (names, paths, words, numbers, booleans, words YAML would read as numbers or dates,
lists of them: most launches) is written here without importing yaml at all (a sixth of a
one-node ``--dump-params``, a fifth of one that sets ``device_id`` to ``'#1'``). Every other
document is PyYAML's (``dump_launch_yaml.py``); tests/test_params_yaml.py checks both against
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
#: text of these characters that PyYAML does not write plain is written single-quoted as it
#: is (no quote to double, no space to fold at): YAML 1.1 reads it as a number or a date
#: (``'0601'``, ``'1.5'``, ``'-1'``, ``'2024-01-31'``), it is a lone ``-`` or starts a
#: document marker (``---``, ``...``), or it starts with an indicator (``'#1'``, ``'@x'``)
_QUOTABLE = re.compile(r"[#&*!|>%@`]?[A-Za-z0-9_./+-]+\Z")
#: what YAML 1.1 (PyYAML's implicit resolvers) reads as an int, a float or a date, for text of
#: the characters above (sexagesimal numbers and full timestamps need a ':' or a space)
_NOT_TEXT_NUMBER = re.compile(
    r"[-+]?(?:0b[01_]+|0[0-7_]+|0|[1-9][0-9_]*|0x[0-9a-fA-F_]+)"         # int
    r"|[-+]?[0-9][0-9_]*\.[0-9_]*(?:[eE][-+][0-9]+)?|\.[0-9][0-9_]*(?:[eE][-+][0-9]+)?"
    r"|[-+]?\.(?:inf|Inf|INF)|\.(?:nan|NaN|NAN)"                            # float
    r"|[0-9]{4}-[0-9]{2}-[0-9]{2}")                                        # date
#: PyYAML folds plain text at a space past this column
_WIDTH = 80
#: PyYAML writes a longer key as ``? key`` (it counts the key's 5-character ``!!str`` tag into
#: its 128-character limit of a simple key)
_SIMPLE_KEY_MAX = 122


def _plain_scalar(value: Any, before: int) -> str | None:
    """``value`` as PyYAML's safe dumper writes it after ``before`` characters of its line,
    when that is one plain, empty or single-quoted scalar of the kinds above (text, exact
    ints, floats, booleans, None); None for anything else."""
    kind = type(value)
    if kind is str:
        if not value:
            return "''"
        if _PLAIN_TEXT.match(value) is not None and value not in _NOT_TEXT:
            return None if " " in value and before + len(value) > _WIDTH else value
        return _quoted_word(value)
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


def _quoted_word(value: str) -> str | None:
    """A word of ``_QUOTABLE``'s characters as PyYAML writes it: plain, unless YAML would
    read it as something else than text (a boolean, null, a number, a date) or as an
    indicator (then single-quoted, see ``_QUOTABLE``); None for any other text."""
    if _QUOTABLE.match(value) is None:
        return None
    if (not value[0].isalnum() and value[0] not in "_./+-"  # a leading indicator
            or value == "-" or value.startswith(("---", "..."))
            or value in _NOT_TEXT or _NOT_TEXT_NUMBER.fullmatch(value) is not None):
        return f"'{value}'"
    return value


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
