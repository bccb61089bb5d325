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
