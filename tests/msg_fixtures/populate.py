"""Fill any genpy-shaped message class with deterministic values, and the genpy side of the
message-class comparison (run by Debian's /usr/bin/python3 with its genpy packages).

The same ``populate`` runs on both sides, so a difference in bytes or ``str()`` is a
difference between the classes, not between the values.
"""
from __future__ import annotations

import io
import json
import sys

_SIGNED = {"int8": 7, "byte": 7, "int16": 15, "int32": 31, "int64": 63}
_UNSIGNED = {"uint8": 8, "char": 8, "uint16": 16, "uint32": 32, "uint64": 64, "bool": 1}
_TEXTS = ["plain", "needs: quoting", "é unicode", "x" * 90 + " wrapped words " * 4, ""]


class Counter:
    def __init__(self):
        self.n = 0

    def next(self) -> int:
        self.n += 1
        return self.n


def _scalar(base: str, c: Counter, env: dict):
    k = c.next()
    if base in ("float32", "float64"):
        return k + 0.25 if base == "float32" else k / 3.0
    if base in _SIGNED:
        return (k * 7919) % (2 ** (_SIGNED[base] - 1)) * (-1 if k % 2 else 1)
    if base == "bool":
        return k % 2 == 0
    if base in _UNSIGNED:
        return (k * 7919) % (2 ** _UNSIGNED[base])
    if base == "string":
        return _TEXTS[k % len(_TEXTS)]
    if base == "time":
        return env["time"](1_700_000_000 + k, k * 1001)
    if base == "duration":
        return env["duration"](k, k * 999)
    return populate(env["msg"](base)(), c, env)


def _value(slot_type: str, c: Counter, env: dict):
    if not slot_type.endswith("]"):
        return _scalar(slot_type, c, env)
    base, size = slot_type[:-1].split("[")
    n = int(size) if size else 2
    if base in ("uint8", "char"):
        return bytes((c.next() * 31 + i) % 256 for i in range(n))
    return [_scalar(base, c, env) for _ in range(n)]


def populate(msg, c: Counter | None = None, env: dict | None = None):
    c = c or Counter()
    for name, slot_type in zip(msg.__slots__, msg._slot_types, strict=True):
        setattr(msg, name, _value(slot_type, c, env))
    return msg


def describe(cls, env: dict) -> dict:
    """md5, layout, populated bytes and str() of one class, and str() after a round trip."""
    msg = populate(cls(), Counter(), env)
    buff = io.BytesIO()
    msg.serialize(buff)
    data = buff.getvalue()
    back = cls()
    back.deserialize(data)
    return {"md5": cls._md5sum, "type": cls._type, "slots": list(cls.__slots__),
            "slot_types": list(cls._slot_types), "has_header": cls._has_header,
            "bytes": data.hex(), "str": str(msg), "str_back": str(back),
            "default_str": str(cls()),
            "constants": sorted([k, repr(v)] for k, v in vars(cls).items() if k.isupper())}


def _genpy_env():
    import importlib

    import genpy

    def msg(type_name):
        pkg, name = type_name.split("/")
        return getattr(importlib.import_module(pkg + ".msg"), name)
    return {"time": genpy.Time, "duration": genpy.Duration, "msg": msg}


def main() -> None:
    """stdin: JSON list of 'pkg/Name' (messages) and 'srv:pkg/Name' (services);
    stdout: JSON {name: describe(...) or {"missing": why}}."""
    import importlib

    env = _genpy_env()
    out = {}
    for name in json.load(sys.stdin):
        try:
            if name.startswith("srv:"):
                pkg, base = name[4:].split("/")
                srv = getattr(importlib.import_module(pkg + ".srv"), base)
                out[name] = {"md5": srv._md5sum,
                             "request": describe(srv._request_class, env),
                             "response": describe(srv._response_class, env)}
            else:
                out[name] = describe(env["msg"](name), env)
        except (ImportError, AttributeError) as exc:
            out[name] = {"missing": str(exc)}
    json.dump(out, sys.stdout)




def dynamic_main() -> None:
    """stdin: JSON {type: full_text}; stdout: describe() of genpy.dynamic's class for each."""
    import genpy
    from genpy.dynamic import generate_dynamic

    out = {}
    for type_name, full_text in json.load(sys.stdin).items():
        classes = generate_dynamic(type_name, full_text)
        env = {"time": genpy.Time, "duration": genpy.Duration, "msg": classes.__getitem__}
        out[type_name] = describe(classes[type_name], env)
    json.dump(out, sys.stdout)


if __name__ == "__main__":
    dynamic_main() if sys.argv[1:] == ["--dynamic"] else main()
