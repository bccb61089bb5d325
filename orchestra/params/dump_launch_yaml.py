"""``roslaunch --dump-params``' document written by PyYAML (``dump_launch.py`` writes the
documents of plain names and numbers itself, without importing yaml).

Scripts diff it against roslaunch's, so it is PyYAML's ``safe_dump`` byte for byte; big
trees are written by libyaml's emitter wherever that gives the same bytes.
"""
from __future__ import annotations

from typing import Any

import yaml


class LaunchParamsDumper(yaml.SafeDumper):
    """PyYAML's safe dumper as ``roslaunch --dump-params`` uses it; bytes (binfile) values
    (also subclasses) as ``!!binary``."""


class CLaunchParamsDumper(yaml.CSafeDumper):
    """The same with libyaml's C emitter: ~4x faster on big trees, and the same bytes
    wherever ``_c_emits_the_same`` says so."""


for _dumper in (LaunchParamsDumper, CLaunchParamsDumper):
    _dumper.add_multi_representer(bytes, yaml.SafeDumper.represent_binary)

# libyaml folds long double-quoted scalars at other columns than PyYAML, and PyYAML counts
# the key's "!!str" tag into its 128-character limit of a simple key where libyaml does not
# (keys of 123-128 characters: ``? key`` in one, ``key:`` in the other), and writes an empty
# key as ``? ''``. Plain, single-quoted and literal scalars come out the same; double quotes
# are only chosen for text with a character outside printable ASCII (line breaks, tabs,
# non-ASCII).
_KEY_LENGTHS_THAT_DIFFER = range(123, 129)


def _c_emits_the_same(value: Any) -> bool:
    """Whether libyaml's emitter writes ``value`` byte for byte as PyYAML's does."""
    if isinstance(value, str):
        return value.isascii() and value.isprintable()
    if isinstance(value, dict):
        return all(isinstance(k, str) and k and len(k) not in _KEY_LENGTHS_THAT_DIFFER
                   and k.isascii() and k.isprintable() and _c_emits_the_same(v)
                   for k, v in value.items())
    if isinstance(value, list):
        return all(_c_emits_the_same(v) for v in value)
    return value is None or isinstance(value, (bool, int, float, bytes))


def yaml_document(params: dict[str, Any]) -> str:
    """The YAML document ``roslaunch --dump-params`` prints for ``params`` (PyYAML's
    safe_dump: block style, sorted keys, ASCII escapes).

    A block mapping at the top is its entries one after the other, so the sorted entries are
    written in runs, each by the emitter that writes it as PyYAML does (a deep tree's long
    names would otherwise send all of it to the slow one)."""
    runs: list[tuple[bool, dict[str, Any]]] = []
    for key in sorted(params):
        fast = _c_emits_the_same({key: params[key]})
        if not runs or runs[-1][0] != fast:
            runs.append((fast, {}))
        runs[-1][1][key] = params[key]
    if not runs:
        return yaml.dump(params, Dumper=LaunchParamsDumper, default_flow_style=False)
    return "".join(yaml.dump(run, Dumper=CLaunchParamsDumper if fast else LaunchParamsDumper,
                             default_flow_style=False) for fast, run in runs)
