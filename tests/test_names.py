"""ROS graph names: the rosgraph.names rules everything else relies on."""
import os
import re
import socket

import pytest

from orchestra import names


@pytest.mark.parametrize("ns, name, joined", [
    ("/", "a", "/a"), ("/ns", "a", "/ns/a"), ("/ns/", "a/b", "/ns/a/b"),
    ("/ns", "/abs", "/abs"), ("/ns", "~priv", "~priv"), ("~", "x", "~x"), ("", "x", "x"),
])
def test_ns_join_leaves_global_and_private_names_alone(ns, name, joined):
    assert names.ns_join(ns, name) == joined


@pytest.mark.parametrize("raw, canonical", [
    ("//a//b/", "/a/b"), ("a//b/", "a/b"), ("/", "/"), ("", ""), ("/$(optenv X /)diag", "/$(optenv X /)diag"),
])
def test_canonicalize_drops_empty_segments_and_trailing_slash(raw, canonical):
    assert names.canonicalize(raw) == canonical


def test_make_global_ns_adds_leading_and_trailing_slash_and_refuses_private():
    assert names.make_global_ns("a/b") == "/a/b/"
    assert names.make_global_ns("/") == "/"
    with pytest.raises(ValueError):
        names.make_global_ns("~x")


@pytest.mark.parametrize("name, legal", [
    ("", True), ("a", True), ("/a/b_c", True), ("~p", True), ("a b", False),
    ("1a", False), ("a//b", False), ("a-b", False), (None, False),
])
def test_is_legal_name_follows_ros_graph_name_rules(name, legal):
    assert names.is_legal_name(name) is legal


def test_resolve_name_handles_relative_global_and_private():
    assert names.resolve_name("chatter", "/ns") == "/ns/chatter"
    assert names.resolve_name("/chatter", "/ns") == "/chatter"
    assert names.resolve_name("~param", "/ns", node_name="/ns/node") == "/ns/node/param"


def test_anonymous_name_is_stable_per_id_and_sanitises_host():
    first = names.anonymous_name("foo-bar")
    assert names.anonymous_name("foo-bar") == first
    assert names.anonymous_name("other") != first
    host = re.sub(r"[.\-:]", "_", socket.gethostname())
    assert re.fullmatch(rf"foo_bar_{re.escape(host)}_{os.getpid()}_\d+", first)


def test_load_mappings_ignores_names_starting_with_a_digit_and_private_params():
    got = names.load_mappings(["3d_sensor:=kinect", "robot:=pr2", "_rate:=10",
                               "__ns:=x", "/abs:=1", "a:=b:=c", "empty:="])
    assert got == {"robot": "pr2", "__ns": "x", "/abs": "1"}
