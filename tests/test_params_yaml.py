"""rosparam YAML rules: safe loading, angle tags, binary, flattening."""
import math

import pytest

from orchestra.errors import OrchestraError
from orchestra.params.yaml import flatten, load_rosparam_yaml


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
