"""Parameter values as rosparam prints them: YAML text for ``get`` and ``dump``.

Scripts parse ``rosparam get`` output, so the exact shape matters: block-style YAML with
sorted keys, a lone scalar without PyYAML's ``...`` document-end marker, one extra newline
after it, binary values as ``!!binary`` base64 blocks. ``pretty`` (``get -p``) is rosparam's
human format: nested ``key: value`` lines, multi-line strings as ``|`` blocks; not YAML-safe.
"""
from __future__ import annotations

import base64
import xmlrpc.client
from typing import Any

import yaml


class ParamDumper(yaml.SafeDumper):
    """PyYAML's safe dumper that also knows the types XML-RPC hands back."""


def _represent_binary(dumper: yaml.SafeDumper, data: xmlrpc.client.Binary) -> yaml.Node:
    text = base64.b64encode(data.data).decode("ascii")
    return dumper.represent_scalar("tag:yaml.org,2002:binary", text, style="|")


def _represent_bytes(dumper: yaml.SafeDumper, data: bytes | bytearray) -> yaml.Node:
    return _represent_binary(dumper, xmlrpc.client.Binary(bytes(data)))


def _represent_datetime(dumper: yaml.SafeDumper, data: xmlrpc.client.DateTime) -> yaml.Node:
    return dumper.represent_scalar("tag:yaml.org,2002:timestamp", str(data.value))


ParamDumper.add_representer(xmlrpc.client.Binary, _represent_binary)
ParamDumper.add_representer(bytes, _represent_bytes)
ParamDumper.add_representer(bytearray, _represent_bytes)
ParamDumper.add_representer(xmlrpc.client.DateTime, _represent_datetime)


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


def dump_launch_params(params: dict[str, Any]) -> str:
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


def dump_yaml(value: Any) -> str:
    """The YAML document ``rosparam dump`` writes for ``value`` (block style, sorted keys)."""
    return yaml.dump(value, Dumper=ParamDumper, default_flow_style=False, allow_unicode=True)


def format_get(value: Any, pretty: bool = False) -> str:
    """What ``rosparam get [-p]`` prints for ``value``, newline-terminated."""
    if pretty and isinstance(value, dict):
        return "".join(_pretty_lines(value, ""))
    if pretty and isinstance(value, str):
        return value + "\n"
    text = dump_yaml(value)
    if text.endswith("\n...\n"):
        text = text[:-5]
    return text + "\n"


def _pretty_lines(value: dict, indent: str) -> list[str]:
    lines: list[str] = []
    for key in sorted(value):
        sub = value[key]
        if isinstance(sub, dict):
            lines.append(f"{indent}{key}:\n")
            lines.extend(_pretty_lines(sub, indent + "  "))
        elif isinstance(sub, str):
            if "\n" in sub:
                lines.append(f"{indent}{key}: |\n")
                lines.extend(f"{indent}  {line}\n" for line in sub.split("\n"))
            else:
                lines.append(f"{indent}{key}: {sub}\n")
        else:
            text = dump_yaml(sub)
            if text.endswith("\n...\n"):
                text = text[:-4]
            lines.append(f"{indent}{key}: {text}")
    return lines
