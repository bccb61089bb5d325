"""Typed values from launch-file strings: ``<param type=...>``, if/unless and bool attributes.

roslaunch's inference for ``type="auto"`` (the default): a string containing ``.`` that
parses as a float is a float, otherwise one that parses as an int is an int; ``true`` /
``false`` in any case are booleans; anything else stays a string. ``type="yaml"`` loads the
text with rosparam's YAML rules and keeps the result whole.
"""
from __future__ import annotations

from typing import Any

from orchestra.errors import clip

PARAM_TYPES = ("auto", "str", "string", "int", "double", "bool", "boolean", "yaml")


def convert_value(value: str, type_: str) -> Any:
    """``value`` converted to ``type_``; ``ValueError`` with a readable reason otherwise."""
    type_ = type_.lower()
    if type_ == "auto":
        try:
            return float(value) if "." in value else int(value)
        except ValueError:
            pass
        lowered = value.lower()
        if lowered in ("true", "false"):
            return lowered == "true"
        return value
    if type_ in ("str", "string"):
        return value
    if type_ in ("int", "double"):
        try:
            return int(value) if type_ == "int" else float(value)
        except ValueError:
            raise ValueError(f"{clip(repr(value))} is not an '{type_}' value") from None
    if type_ in ("bool", "boolean"):
        lowered = value.lower().strip()
        if lowered in ("true", "1"):
            return True
        if lowered in ("false", "0"):
            return False
        raise ValueError(f"{clip(repr(value))} is not a '{type_}' value (true/false/1/0)")
    if type_ == "yaml":
        from orchestra.params.yaml import load_yaml_value
        return load_yaml_value(value, "<yaml param>")
    raise ValueError(f"unknown type '{type_}' (one of {', '.join(PARAM_TYPES)})")


def bool_attribute(value: str | None, default: bool, label: str) -> bool:
    """A ``true``/``false`` attribute (case-insensitive); empty or other text is an error."""
    if value is None:
        return default
    lowered = value.lower()
    if lowered == "true":
        return True
    if lowered == "false":
        return False
    if not value:
        raise ValueError(f"bool value for {label} must be non-empty")
    raise ValueError(f"invalid bool value for {label}: {clip(value)}")


_SIZE_UNITS = {"": 1, "b": 1, "k": 1000, "kb": 1000, "kib": 1024, "m": 1000**2, "mb": 1000**2,
               "mib": 1024**2, "g": 1000**3, "gb": 1000**3, "gib": 1024**3}


def size_attribute(value: str | None, default: int | None, label: str) -> int | None:
    """A byte size as rosmon's ``memory-limit`` takes it: ``100000000``, ``15 MB``, ``1GiB``."""
    if value is None:
        return default
    text = value.strip()
    number = text.rstrip("BbKkMmGgIi ")
    unit = text[len(number):].strip().lower()
    try:
        size = float(number) * _SIZE_UNITS[unit]
    except (KeyError, ValueError):
        raise ValueError(f"invalid size for {label}: {clip(repr(value))} (bytes, or a number with "
                         "kB/MB/GB/KiB/MiB/GiB)") from None
    return int(size)


def float_attribute(value: str | None, default: float, label: str) -> float:
    if value is None:
        return default
    if not value:
        raise ValueError(f"value for {label} must be non-empty")
    try:
        return float(value)
    except ValueError:
        raise ValueError(f"invalid float value for {label}: {clip(value)}") from None
