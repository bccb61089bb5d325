"""Message classes against genpy's: for every standard type Debian's genpy also provides,
the same md5, layout, serialized bytes of a populated instance and the same str().

genpy's side runs in Debian's /usr/bin/python3 (python3-std-msgs, geometry, sensor, nav,
actionlib_msgs, std_srvs, tf2_msgs...); both sides fill the instance with the same
``tests/msg_fixtures/populate.py``. Types genpy does not have here are skipped, with the
reason.
"""
from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from orchestra.node import msgdefs
from orchestra.node.msg import get_message_class, get_service_class
from orchestra.node.rostime import Duration, Time

FIXTURES = Path(__file__).resolve().parent / "msg_fixtures"
sys.path.insert(0, str(FIXTURES))
import populate  # noqa: E402

SYSTEM_PYTHON = "/usr/bin/python3"
MESSAGES = sorted(msgdefs.standard_texts()) + sorted(
    f"{pkg}/{name}" for pkg in ("tf2_msgs",) for name in msgdefs.package_types(pkg, "msg"))
SERVICES = sorted(f"{pkg}/{name}" for pkg in os.listdir(msgdefs.DEFINITIONS)
                  for name in msgdefs.package_types(pkg, "srv"))
OURS = {"time": Time, "duration": Duration, "msg": get_message_class}


@pytest.fixture(scope="module")
def genpy_side() -> dict:
    if not os.path.exists(SYSTEM_PYTHON):
        pytest.skip("no /usr/bin/python3 (Debian's genpy is the reference)")
    names = MESSAGES + [f"srv:{s}" for s in SERVICES]
    out = subprocess.run([SYSTEM_PYTHON, str(FIXTURES / "populate.py")], input=json.dumps(names),
                         capture_output=True, text=True, timeout=300, env={"PATH": "/usr/bin"})
    if out.returncode != 0:
        pytest.skip(f"genpy's side failed (is python3-genpy installed?): {out.stderr[-300:]}")
    return json.loads(out.stdout)


def _reference(genpy_side: dict, name: str) -> dict:
    ref = genpy_side[name]
    if "missing" in ref:
        pytest.skip(f"Debian's genpy has no {name} here: {ref['missing']}")
    return ref


@pytest.mark.parametrize("msg_type", MESSAGES)
def test_message_class_matches_genpy(genpy_side, msg_type):
    ref = _reference(genpy_side, msg_type)
    assert populate.describe(get_message_class(msg_type), OURS) == ref


@pytest.mark.parametrize("srv_type", SERVICES)
def test_service_classes_match_genpy(genpy_side, srv_type):
    ref = _reference(genpy_side, f"srv:{srv_type}")
    cls = get_service_class(srv_type)
    assert cls._md5sum == ref["md5"]
    assert populate.describe(cls._request_class, OURS) == ref["request"]
    assert populate.describe(cls._response_class, OURS) == ref["response"]


def test_most_standard_types_are_compared(genpy_side):
    compared = [n for n in MESSAGES if "missing" not in genpy_side[n]]
    assert len(compared) >= 100, f"only {len(compared)} types have a genpy class here"


EDGE_CASES = {
    "l10_edge/Inner.msg": "# an inner type\nduration[] waits\nchar[3] code\nbyte[] signed\n",
    "l10_edge/Everything.msg": (
        "# every kind of field and constant\n"
        "int8 NEG=-5\nuint8 HEX_LIKE=255\nfloat64 PI=3.14159\nstring NOTE= a # kept\n"
        "bool FLAG=1\nHeader header\nbool[] flags\nint16[4] quad\nfloat32[] values\n"
        "string[] names\nstring[2] pair\ntime[2] stamps\nInner inner\nInner[2] inners\n"
        "geometry_msgs/Point[] points\nuint64 big  # trailing comment\nuint8[4] raw\n"),
}


def test_user_definitions_match_genpys_dynamic_classes(tmp_path, monkeypatch, genpy_side):
    """genpy.dynamic builds classes from a full text, as rostopic does for unknown types: the
    same definitions must give the same classes here (constants, comments, every array)."""
    from orchestra.node.msg import Registry
    from orchestra.packages.index import reset_index

    for rel, text in EDGE_CASES.items():
        path = tmp_path / rel.split("/")[0] / "msg" / rel.split("/")[1]
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text)
    (tmp_path / "l10_edge" / "package.xml").write_text(
        "<package><name>l10_edge</name></package>")
    monkeypatch.setenv("ROS_PACKAGE_PATH", str(tmp_path))
    reset_index()
    try:
        registry = Registry()
        cls = registry.message_class("l10_edge/Everything")
        out = subprocess.run([SYSTEM_PYTHON, str(FIXTURES / "populate.py"), "--dynamic"],
                             input=json.dumps({cls._type: cls._full_text}), capture_output=True,
                             text=True, timeout=120, env={"PATH": "/usr/bin"})
        assert out.returncode == 0, out.stderr[-800:]
        env = dict(OURS, msg=registry.message_class)
        assert populate.describe(cls, env) == json.loads(out.stdout)[cls._type]
    finally:
        reset_index()
