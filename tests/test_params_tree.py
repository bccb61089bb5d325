"""The parameter tree follows rosmaster's parameter server semantics."""
from __future__ import annotations

import xmlrpc.client

import pytest

from orchestra.params.tree import ParamTree, ParamValueError, canonical, check_value, namespace_of, resolve


@pytest.fixture
def tree() -> ParamTree:
    return ParamTree()


def test_names_canonicalise_and_resolve_relative_to_caller():
    assert canonical("/a//b/") == "/a/b"
    assert namespace_of("/a/b/node") == "/a/b/"
    assert namespace_of("/node") == "/"
    assert resolve("x", "/ns/node") == "/ns/x"
    assert resolve("~x", "/ns/node") == "/ns/node/x"
    assert resolve("/g", "/ns/node") == "/g"
    assert resolve("", "/ns/node") == "/ns/"


def test_get_namespace_returns_dict_of_children(tree):
    tree.set("/gains/P", 10.0)
    tree.set("/gains/I", 1.0)
    assert tree.get("/gains") == {"P": 10.0, "I": 1.0}
    assert tree.get("/") == {"gains": {"P": 10.0, "I": 1.0}}


def test_setting_dict_replaces_subtree_instead_of_merging(tree):
    tree.set("/a/x", 1)
    tree.set("/a", {"y": 2})
    assert tree.get("/a") == {"y": 2}
    assert not tree.has("/a/x")


def test_setting_below_a_leaf_turns_it_into_a_namespace(tree):
    tree.set("/a", 1)
    tree.set("/a/b", 2)
    assert tree.get("/a") == {"b": 2}


def test_set_root_requires_a_dict(tree):
    tree.set("/", {"k": 1})
    assert tree.get("/k") == 1
    with pytest.raises(TypeError):
        tree.set("/", 3)


def test_get_missing_and_delete_missing_raise_keyerror(tree):
    tree.set("/a/b", 1)
    with pytest.raises(KeyError):
        tree.get("/a/c")
    with pytest.raises(KeyError):
        tree.get("/a/b/c")
    with pytest.raises(KeyError):
        tree.delete("/nope/x")
    with pytest.raises(KeyError):
        tree.delete("/")


def test_delete_namespace_removes_everything_below(tree):
    tree.set("/a/b/c", 1)
    tree.set("/a/d", 2)
    tree.delete("/a/b")
    assert tree.get("/a") == {"d": 2}


def test_names_lists_leaves_only(tree):
    tree.set("/a/b", 1)
    tree.set("/empty", {})
    tree.set("/c", [1, 2])
    assert sorted(tree.names()) == ["/a/b", "/c"]


def test_returned_dicts_are_copies(tree):
    tree.set("/a/b", 1)
    got = tree.get("/a")
    got["b"] = 99
    assert tree.get("/a/b") == 1
    value = {"x": {"y": 1}}
    tree.set("/v", value)
    value["x"]["y"] = 2
    assert tree.get("/v/x/y") == 1


def test_search_starts_in_callers_private_namespace_and_goes_up(tree):
    tree.set("/robot/arm/node/rate", 1)
    tree.set("/robot/rate", 2)
    tree.set("/rate", 3)
    assert tree.search("/robot/arm/node", "rate") == "/robot/arm/node/rate"
    assert tree.search("/robot/arm/other", "rate") == "/robot/rate"
    assert tree.search("/top", "rate") == "/rate"
    assert tree.search("/top", "missing") is None


def test_search_matches_on_first_segment_of_key(tree):
    tree.set("/robot/limits/speed", 1)
    assert tree.search("/robot/arm/node", "limits/accel") == "/robot/limits/accel"


def test_search_global_key_is_a_has_check_and_private_key_is_refused(tree):
    tree.set("/g", 1)
    assert tree.search("/a/b", "/g") == "/g"
    assert tree.search("/a/b", "/h") is None
    with pytest.raises(ValueError):
        tree.search("/a/b", "~x")


def test_subscribe_returns_current_value_or_empty_dict(tree):
    tree.set("/a/b", 5)
    assert tree.subscribe("/a/b", "/n", "http://h:1/") == 5
    assert tree.subscribe("/a", "/n", "http://h:1/") == {"b": 5}
    assert tree.subscribe("/missing", "/n", "http://h:1/") == {}


def test_set_notifies_subscribers_of_written_key_and_of_enclosing_namespace(tree):
    tree.subscribe("/a/b", "/n1", "http://n1/")
    tree.subscribe("/a", "/n2", "http://n2/")
    updates = tree.set("/a/b", 7)
    got = {(u.subscribers, u.key, u.value) for u in updates}
    assert got == {((("/n1", "http://n1/"),), "/a/b/", 7),
                   ((("/n2", "http://n2/"),), "/a/b/", 7)}


def test_a_leaf_write_reaches_the_root_and_enclosing_subscriptions_only(tree):
    for key, node in [("/", "/root"), ("/a", "/a"), ("/ab", "/ab"), ("/a/b/c", "/below"),
                      ("/a/bb", "/sibling")]:
        tree.subscribe(key, node, f"http://{node.strip('/') or 'r'}/")
    got = {u.subscribers[0][0] for u in tree.set("/a/b", 1)}
    assert got == {"/root", "/a"}


def test_setting_a_dict_notifies_subscribers_inside_it_with_their_own_value(tree):
    tree.subscribe("/a/b/c", "/n", "http://n/")
    tree.subscribe("/a/gone", "/m", "http://m/")
    tree.set("/a/gone", 1)
    updates = tree.set("/a", {"b": {"c": 3}})
    got = {(u.key, repr(u.value)) for u in updates}
    assert ("/a/b/c/", "3") in got
    assert ("/a/gone/", "{}") in got  # no longer in the new dict: deleted


def test_delete_notifies_with_empty_dict(tree):
    tree.set("/a/b", 1)
    tree.subscribe("/a/b", "/n", "http://n/")
    updates = tree.delete("/a")
    assert [(u.key, u.value) for u in updates] == [("/a/b/", {})]


def test_unsubscribe_stops_updates(tree):
    tree.subscribe("/a", "/n", "http://n/")
    assert tree.unsubscribe("/a", "/n", "http://n/") is True
    assert tree.unsubscribe("/a", "/n", "http://n/") is False
    assert tree.set("/a", 1) == []


@pytest.mark.parametrize("value", [2 ** 31, -(2 ** 31) - 1, None, {1: "x"}, {"a": [1, None]},
                                   object()])
def test_values_xmlrpc_cannot_carry_are_refused_naming_the_param(value):
    with pytest.raises(ParamValueError) as info:
        check_value("/robot/p", value)
    assert "/robot/p" in str(info.value)


@pytest.mark.parametrize("value", [2 ** 31 - 1, -(2 ** 31), 1.5e300, True, "s", b"\x00",
                                   xmlrpc.client.Binary(b"x"), [1, "a", {"k": 2.0}], {}])
def test_values_xmlrpc_can_carry_are_accepted(value):
    check_value("/p", value)


def test_nested_bad_value_is_named_by_its_full_path():
    with pytest.raises(ParamValueError, match=r"/ns/outer/inner\[1\]"):
        check_value("/ns", {"outer": {"inner": [0, 2 ** 40]}})
