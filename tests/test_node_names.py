"""Graph-name rules a node applies: resolution, remap arguments, private params."""
from __future__ import annotations

import os

import pytest

from orchestra.node import names


@pytest.mark.parametrize("name,expected", [
    ("chatter", "/ns/chatter"),
    ("/chatter", "/chatter"),
    ("~param", "/ns/node/param"),
    ("", "/ns"),
    ("a//b/", "/ns/a/b"),
])
def test_resolve_relative_global_private(name, expected):
    assert names.resolve(name, "/ns/", "/ns/node") == expected


def test_remaps_apply_to_the_resolved_name():
    remaps = names.resolve_remaps({"chatter": "/other", "~in": "out"}, "/ns/", "/ns/node")
    assert remaps == {"/ns/chatter": "/other", "/ns/node/in": "/ns/out"}
    assert names.resolve("chatter", "/ns/", "/ns/node", remaps) == "/other"
    assert names.resolve("/ns/chatter", "/ns/", "/ns/node", remaps) == "/other"
    assert names.resolve("~in", "/ns/", "/ns/node", remaps) == "/ns/out"


def test_parse_args_splits_remaps_specials_private_params_and_plain_args():
    parsed = names.parse_args(["prog", "a:=b", "__name:=n", "__ns:=/x", "_rate:=10",
                               "--flag", "__log:=/tmp/l.log", "value"])
    assert parsed.remaps == {"a": "b"}
    assert parsed.special == {"__name": "n", "__ns": "/x", "__log": "/tmp/l.log"}
    assert parsed.private_params == {"rate": "10"}
    assert parsed.argv == ["prog", "--flag", "value"]


def test_namespace_forms():
    assert names.make_global_ns("robot") == "/robot/"
    assert names.make_global_ns("/") == "/"
    assert names.namespace_of("/a/b") == "/a/"
    assert names.namespace_of("/b") == "/"


@pytest.mark.parametrize("name,ok", [("a/b", True), ("~x", True), ("1a", False),
                                     ("a-b", False), ("/a//b", False)])
def test_legal_names(name, ok):
    assert names.is_legal_name(name) is ok


def test_anonymous_names_carry_the_pid_like_rospy():
    base, pid, millis = names.anonymous_name("cli").split("_")
    assert (base, pid) == ("cli", str(os.getpid())) and millis.isdigit()
