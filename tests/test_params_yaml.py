"""rosparam YAML rules: safe loading, angle tags, binary, flattening."""
import math

import pytest
import yaml
from hypothesis import given, settings
from hypothesis import strategies as st

from orchestra.errors import OrchestraError
from orchestra.params.dump_launch import dump_launch_params, plain_document
from orchestra.params.dump_launch_yaml import LaunchParamsDumper, _c_emits_the_same
from orchestra.params.yaml import (
    RosparamLoader,
    RosparamYamlError,
    _check_bounds,
    flatten,
    load_rosparam_yaml,
    load_yaml_value,
)


def test_degrees_and_radians_tags_become_radians():
    data = load_rosparam_yaml("a: !degrees 180\nb: !radians pi/2\nc: deg(90)\nd: rad(2*pi)\n")
    assert data["a"] == pytest.approx(math.pi)
    assert data["b"] == pytest.approx(math.pi / 2)
    assert data["c"] == pytest.approx(math.pi / 2)
    assert data["d"] == pytest.approx(2 * math.pi)


def test_radians_expression_cannot_call_python():
    with pytest.raises(OrchestraError):
        load_rosparam_yaml("a: !radians __import__('os').getcwd()\n")


def test_binary_tag_loads_bytes():
    assert load_rosparam_yaml("b: !!binary aGVsbG8=\n") == {"b": b"hello"}


def test_python_object_tags_are_refused():
    with pytest.raises(OrchestraError) as info:
        load_rosparam_yaml("x: !!python/object/apply:os.system ['true']\n", "evil.yaml")
    assert "evil.yaml:1" in str(info.value)


def test_yaml_1_1_scalars_match_rosparam():
    data = load_rosparam_yaml("a: yes\nb: 1e5\nc: 1.5e+3\nd: '10'\ne: 1.5e3\n")
    assert data == {"a": True, "b": "1e5", "c": 1500.0, "d": "10", "e": "1.5e3"}


def test_empty_document_is_an_empty_dict():
    assert load_rosparam_yaml("# nothing\n") == {}


def test_syntax_error_names_file_and_line():
    with pytest.raises(OrchestraError) as info:
        load_rosparam_yaml("a: 1\nb: [1, 2\n", "conf.yaml")
    assert str(info.value).startswith("conf.yaml:")


def test_flatten_unrolls_dicts_to_leaves_and_skips_empty_dicts():
    assert flatten("/ns", {"a": {"b": 1, "c": [1, 2]}, "d": "x", "e": {}}) == [
        ("/ns/a/b", 1), ("/ns/a/c", [1, 2]), ("/ns/d", "x")]


@pytest.mark.parametrize("text, position, why", [
    ("a: " + "[" * 500 + "]" * 500 + "\n", (1, 103), "nested more than 100"),
    ("a:\n  b: " + "{c: " * 200 + "1" + "}" * 200 + "\n", (2, None), "nested more than 100"),
    ("a: &x [*x]\n", None, "nested more than 100"),
    ("a: 1\nb: " + "1" * 5000 + "\n", (2, 4), "integer of 5000 characters"),
    ("a: 0x" + "f" * 100000 + "\n", (1, 4), "integer of"),
    ("a: 2001-12-14t21:59:43.10-99:00\n", (1, 4), "invalid timestamp value"),
    ("a: !radians 9**9**9\n", (1, 4), "radian"),
    ("a: !radians " + "-" * 5000 + "1\n", (1, 4), "radian"),
    ('a: 1\nb: "x\x01"\n', (2, 6), r"U\+0001"),
], ids=["deep-list", "deep-map", "self-alias", "long-int", "long-hex", "timestamp",
        "radians-power", "radians-nesting", "control-char"])
def test_hostile_values_are_refused_at_their_position(text, position, why):
    with pytest.raises(OrchestraError, match=why) as info:
        load_rosparam_yaml(text, "p.yaml")
    location = info.value.location
    assert location.file == "p.yaml" and location.line is not None
    if position is not None:
        assert location.line == position[0]
        assert position[1] is None or location.column == position[1]


# scalars written plainly, each resolving to another tag (int, float, bool, null, str, timestamp)
_WORDS = st.sampled_from(["1", "-2", "0x1f", "1_000", "017", "1.5", "1e3", "1.0e3", ".nan", ".inf",
                          "yes", "No", "off", "~", "null", "x", "abc", "'q'", "2001-12-14",
                          "1:20", "<<", "=", "1" * 1301])


def _flow(children):
    return children.map(lambda c: "[" + ", ".join(c) + "]")


_FLOW = st.recursive(_WORDS, lambda inner: _flow(st.lists(inner, max_size=3)) | st.lists(
    st.tuples(_WORDS, inner), max_size=3).map(
        lambda kv: "{" + ", ".join(f"{k}: {v}" for k, v in kv) + "}"), max_leaves=8)


def _two_passes(text):
    """What load_yaml_value returned before its one-pass builder: the bounds checked over the
    node graph, then PyYAML's constructor."""
    loader = RosparamLoader(text)
    try:
        node = loader.get_single_node()
        _check_bounds(node, "<yaml>")
        return loader.construct_document(node)
    finally:
        loader.dispose()


_NEAR_THE_BOUND = st.integers(93, 99) | st.integers(0, 99)  # levels of lists around an alias


@settings(max_examples=400, deadline=None)
@given(_FLOW, _NEAR_THE_BOUND, _NEAR_THE_BOUND, _FLOW)
def test_one_pass_build_is_pyyamls_constructor_with_aliases_near_the_depth_bound(
        shared, deep_a, deep_b, other):
    """Values, types and which collections are one object (an alias names one again: yaml.dump
    writes it with an anchor) are PyYAML's; a document is refused exactly when it is too deep
    or holds a too long integer wherever an alias puts it."""
    text = (f"a: &A {shared}\nb: {'[' * deep_a}*A{']' * deep_a}\nc: {other}\n"
            f"d: [{'[' * deep_b}*A{']' * deep_b}, *A]\n")
    try:
        expected = yaml.dump(_two_passes(text))
    except (RosparamYamlError, yaml.YAMLError, ValueError) as exc:
        with pytest.raises(OrchestraError) as info:
            load_yaml_value(text)
        assert not isinstance(exc, RosparamYamlError) or exc.message == info.value.message
        return
    assert yaml.dump(load_yaml_value(text)) == expected


_TEXT = st.text(alphabet=st.sampled_from(list("ab :#-'\"\\{}[],&*!|>%@`?=~.09eE+\n\t\x85é")),
                max_size=150)
_VALUES = st.recursive(
    st.none() | st.booleans() | st.integers() | st.floats() | _TEXT | st.binary(max_size=300),
    lambda inner: st.lists(inner, max_size=4) | st.dictionaries(_TEXT, inner, max_size=4),
    max_leaves=12)


@settings(max_examples=300, deadline=None)
@given(st.dictionaries(_TEXT | st.text(alphabet="a/", min_size=118, max_size=134), _VALUES,
                       max_size=5))
def test_dump_params_is_pyyamls_safe_dump_byte_for_byte(params):
    """--dump-params takes libyaml's emitter only where it writes PyYAML's bytes."""
    assert dump_launch_params(params) == yaml.dump(params, Dumper=LaunchParamsDumper,
                                                   default_flow_style=False)


_NAMEISH = st.text(alphabet=st.sampled_from(list("abyYnNoOfFtTlLuUeE_/.-019: ~<=#")),
                   max_size=12)
_SCALARS = (st.none() | st.booleans() | st.integers() | st.floats() | _NAMEISH
            | st.text(alphabet="/a ", min_size=60, max_size=100)
            | st.text(alphabet="/a", min_size=70, max_size=300))


_WORDISH = st.text(alphabet=st.sampled_from(list("0123456789_.-+xXbBoeEaAfFinINT#@`!|/")),
                   max_size=10)


@settings(max_examples=500, deadline=None)
@given(st.dictionaries(_NAMEISH, _WORDISH | st.lists(_WORDISH, max_size=3), max_size=6))
def test_dump_params_of_number_like_words_is_pyyamls(params):
    """Words YAML 1.1 reads as numbers or dates, or that start with an indicator, are
    single-quoted as PyYAML quotes them; others of those characters are plain."""
    expected = yaml.dump(params, Dumper=LaunchParamsDumper, default_flow_style=False)
    assert dump_launch_params(params) == expected
    assert plain_document(params) in (None, expected)


@settings(max_examples=500, deadline=None)
@given(st.dictionaries(_NAMEISH | st.text(alphabet="/a", min_size=118, max_size=126),
                       _SCALARS | st.lists(_SCALARS, max_size=3), max_size=6))
def test_dump_params_of_plain_names_and_numbers_is_pyyamls_too(params):
    """The documents written without yaml (names, paths, words, numbers and lists of them)
    are PyYAML's bytes, and so are the ones it hands to yaml."""
    expected = yaml.dump(params, Dumper=LaunchParamsDumper, default_flow_style=False)
    assert dump_launch_params(params) == expected
    assert plain_document(params) in (None, expected)


def test_a_document_of_names_and_numbers_is_written_without_yaml():
    params = {"/a/rate": 10, "/a/frame": "base_link", "/a/gain": 0.5, "/b/path": "/x/y.yaml",
              "/b/on": True, "/b/big": 1e17, "/c": None, "/d": "", "/e": ["Motor State", 2],
              "/f": [], "/g": "Input Ports", "/h/device_id": "#1", "/h/product": "0601",
              "/h/vendor": "1d27", "/h/yes": "yes", "/h/ten": "10", "/i": ["1e-9", "1.0e-9"],
              "/j": "2024-01-31", "/k": "-", "/m": "10.68.0.20"}
    assert plain_document(params) == yaml.dump(params, Dumper=LaunchParamsDumper,
                                               default_flow_style=False)
    assert plain_document({}) == "{}\n"
    for other in ({"/a": "a: b"}, {"/a": "a#b"}, {"/a": "'q'"}, {"/a": [[1]]}, {"/a": {}},
                  {"/" + "k" * 122: 1}, {"/a": b"x"}, {"/a": "~"}, {"/a": "a " * 40 + "b"},
                  {"/a b": 1}, {"/a": " a"}):
        assert plain_document(other) is None, other


def test_dump_params_takes_the_c_emitter_for_plain_text_and_numbers():
    assert _c_emits_the_same({"a": {"b": ["x y", 1, 2.5, None, True, b"\x00"]}})
    assert not _c_emits_the_same({"a": "two\nlines"})
    assert not _c_emits_the_same({"": 1})
    assert not _c_emits_the_same({"k" * 125: 1})
    assert _c_emits_the_same({"k" * 200: 1})
