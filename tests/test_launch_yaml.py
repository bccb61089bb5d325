"""The YAML launch front end: schema, lossless scalar text, locations, refusals."""
from __future__ import annotations

import pytest

from orchestra.errors import Location, OrchestraError
from orchestra.launch.entity import Entity
from orchestra.launch.yaml import parse_file, parse_string


def parse(text: str) -> Entity:
    return parse_string(text, "t.launch.yaml")


def error_of(text: str) -> OrchestraError:
    with pytest.raises(OrchestraError) as info:
        parse(text)
    return info.value


def test_launch_children_become_entities_in_order():
    root = parse("launch:\n  - arg: {name: a}\n  - node: {pkg: p, type: t, name: n}\n")
    assert root.tag == "launch"
    assert [c.tag for c in root.children] == ["arg", "node"]
    assert root.children[1].attributes == {"pkg": "p", "type": "t", "name": "n"}


def test_attribute_order_is_file_order():
    root = parse("launch:\n  - node: {name: n, type: t, pkg: p}\n")
    assert list(root.children[0].attributes) == ["name", "type", "pkg"]


@pytest.mark.parametrize("written, raw", [
    ("true", "true"), ("True", "True"), ("1.10", "1.10"), ("0x1F", "0x1F"), ("1e3", "1e3"),
    ("~", "~"), ("null", "null"), ("", ""), ("'007'", "007"), ('"a\\tb"', "a\tb"),
    ("$(find pkg)/x.yaml", "$(find pkg)/x.yaml"), ("2001-12-14", "2001-12-14"),
    ("-1", "-1"), (".inf", ".inf"), ("yes", "yes"),
])
def test_scalar_attribute_is_the_text_as_written(written, raw):
    root = parse(f"launch:\n  - param:\n      name: p\n      value: {written}\n")
    assert root.children[0].get("value") == raw


def test_element_text_goes_under_text_key_verbatim():
    root = parse("launch:\n  - rosparam:\n      command: load\n      text: |\n"
                 "        a: 1\n        b: !degrees 90\n")
    rosparam = root.children[0]
    assert rosparam.attributes == {"command": "load"}
    assert rosparam.text == "a: 1\nb: !degrees 90\n"


def test_children_key_nests_elements():
    root = parse("launch:\n  - group:\n      ns: g\n      children:\n"
                 "        - node: {pkg: p, type: t, name: n}\n")
    group = root.children[0]
    assert group.attributes == {"ns": "g"}
    assert [c.tag for c in group.children] == ["node"]


def test_list_body_is_children_without_attributes():
    root = parse("launch:\n  - group:\n    - param: {name: a, value: 1}\n")
    assert root.children[0].attributes == {}
    assert root.children[0].children[0].tag == "param"


def test_nested_lists_are_flattened_into_children():
    root = parse("launch:\n  - - arg: {name: a}\n    - arg: {name: b}\n  - arg: {name: c}\n")
    assert [c.get("name") for c in root.children] == ["a", "b", "c"]


def test_empty_element_body_is_an_element_with_nothing():
    root = parse("launch:\n  - group:\n")
    assert root.children == [Entity("group", location=root.children[0].location)]


def test_ros2_aliases_map_to_roslaunch_attribute_names():
    root = parse("launch:\n  - node: {pkg: p, exec: t, name: n, namespace: ns}\n"
                 "  - arg: {name: a, description: the a}\n")
    assert root.children[0].attributes == {"pkg": "p", "type": "t", "name": "n", "ns": "ns"}
    assert root.children[1].get("doc") == "the a"


def test_alias_and_canonical_name_together_is_an_error():
    err = error_of("launch:\n  - node: {pkg: p, exec: t, type: u}\n")
    assert "type" in err.message
    assert err.location == Location("t.launch.yaml", 2, 29)


def test_ros2_style_child_lists_under_a_tag_key():
    root = parse("launch:\n  - node:\n      pkg: p\n      type: t\n      param:\n"
                 "        - {name: a, value: 1}\n        - {name: b, value: 2}\n"
                 "      remap: {from: x, to: y}\n")
    node = root.children[0]
    assert [(c.tag, c.get("name") or c.get("from")) for c in node.children] == [
        ("param", "a"), ("param", "b"), ("remap", "x")]


def test_structured_value_for_a_non_tag_key_is_refused_with_hint():
    err = error_of("launch:\n  - param:\n      name: p\n      value: [1, 2]\n")
    assert "must be a single value" in err.message and "value" in err.message
    assert err.location.line == 4


def test_merge_keys_share_attributes_and_own_keys_win():
    root = parse("launch:\n  - node:\n      <<: {output: screen, respawn: 'true'}\n"
                 "      pkg: p\n      respawn: 'false'\n")
    assert root.children[0].attributes == {"output": "screen", "respawn": "false", "pkg": "p"}


def test_entities_carry_file_line_and_column_of_their_tag():
    root = parse("launch:\n  - arg: {name: a}\n  - group:\n      children:\n"
                 "        - node: {pkg: p, type: t}\n")
    assert root.location == Location("t.launch.yaml", 1, 1)
    assert root.children[0].location == Location("t.launch.yaml", 2, 5)
    assert root.children[1].children[0].location == Location("t.launch.yaml", 5, 11)


def test_attribute_locations_are_recorded_per_attribute():
    root = parse("launch:\n  - node:\n      pkg: p\n      typo: t\n")
    assert root.children[0].attribute_locations["typo"] == Location("t.launch.yaml", 4, 7)


def test_python_object_tag_is_refused():
    err = error_of("launch:\n  - param: !!python/object:os.system {name: x}\n")
    assert "python/object" in err.message
    assert err.location.line == 2


def test_python_tag_inside_a_value_is_refused():
    err = error_of("launch:\n  - param: {name: x, value: !!python/name:os.system ''}\n")
    assert "not allowed" in err.message


def test_custom_tag_in_inline_rosparam_text_is_just_text():
    root = parse("launch:\n  - rosparam:\n      text: 'angle: !degrees 90'\n")
    assert root.children[0].text == "angle: !degrees 90"


def test_malformed_yaml_reports_file_and_line():
    err = error_of("launch:\n  - node: {pkg: p\n")
    assert err.location.file == "t.launch.yaml"
    assert err.location.line is not None
    assert "invalid YAML" in err.message


def test_duplicate_key_is_an_error_not_last_wins():
    err = error_of("launch:\n  - node:\n      name: a\n      name: b\n")
    assert "duplicate key 'name'" in err.message
    assert err.location.line == 4


@pytest.mark.parametrize("text, fragment", [
    ("", "empty launch file"),
    ("# only a comment\n", "empty launch file"),
    ("- launch: []\n", "single key 'launch:'"),
    ("launch: []\nother: []\n", "single key 'launch:'"),
    ("launch: [a]\n", "one element"),
    ("launch:\n  - {node: {}, arg: {}}\n", "exactly one key"),
    ("launch:\n  - node: 3\n", "mapping of attributes"),
    ("launch:\n  - rosparam: {text: {a: 1}}\n", "must be a string"),
    ("launch:\n  - group: {children: {node: {}}}\n", "must be a list"),
    ("launch: []\n---\nlaunch: []\n", "exactly one document"),
    ("launch:\n  - {[a]: 1}\n", "plain name"),
])
def test_wrong_shape_is_a_located_error(text, fragment):
    err = error_of(text)
    assert fragment in err.message
    assert err.location is not None and err.location.file == "t.launch.yaml"


def test_list_of_attribute_maps_under_a_tag_explains_the_one_item_per_element_rule():
    err = error_of("launch:\n  - param: [{name: a, value: 1}, {name: b, value: 2}]\n")
    assert "one '- param:' item each" in err.message
    assert (err.location.line, err.location.column) == (2, 13)


def test_aliases_are_copied_into_the_tree():
    root = parse("launch:\n  - group: &g [{arg: {name: a}}]\n  - group: *g\n")
    assert [c.children[0].get("name") for c in root.children] == ["a", "a"]


@pytest.mark.parametrize("text", [
    "launch: &a [*a]\n",
    "launch:\n  - group: &g {children: [{group: *g}]}\n",
])
def test_recursive_alias_is_refused(text):
    assert "recursive alias" in error_of(text).message


def test_alias_bomb_is_refused_not_expanded():
    lines = ["launch:", "  - group: &a0 [{arg: {name: x}}, {arg: {name: y}}]"]
    for i in range(1, 10):
        refs = ", ".join([f"*a{i - 1}"] * 10)
        lines.append(f"  - group: &a{i} [{refs}]")
    assert "more than" in error_of("\n".join(lines) + "\n").message


def test_self_merge_is_refused_without_a_traceback():
    err = error_of("launch:\n  - node: &n {pkg: p, <<: *n}\n")
    assert err.location.file == "t.launch.yaml"


def test_parse_file_reads_from_disk_and_names_the_path(tmp_path):
    path = tmp_path / "x.launch.yaml"
    path.write_text("launch:\n  - arg: {name: a}\n")
    root = parse_file(str(path))
    assert root.children[0].location.file == str(path)


def test_parse_file_missing_is_an_orchestra_error(tmp_path):
    with pytest.raises(OrchestraError) as info:
        parse_file(str(tmp_path / "none.launch.yaml"))
    assert "not found" in info.value.message


def test_example_yaml_launch_file_resolves_like_its_xml_original(compat_dir):
    """launch/turtle_tf_demo.launch.yaml, written by hand with ROS 2 spellings, launches
    exactly what turtle_tf's XML demo does."""
    from conftest import REPO

    from orchestra.launch.interpreter import load_launch

    def plan_of(path):
        data = load_launch(str(path), no_exec=True).to_json()
        for node in data["nodes"]:
            node["filename"] = None
        data["files_loaded"] = []
        return data

    assert plan_of(REPO / "launch" / "turtle_tf_demo.launch.yaml") == \
        plan_of(compat_dir / "ws" / "turtle_tf" / "launch" / "turtle_tf_demo.launch")


@pytest.mark.parametrize("loader", ["SafeLoader", "CSafeLoader"])
def test_pure_and_libyaml_composers_read_the_same_entities(loader, monkeypatch):
    import yaml as pyyaml

    from orchestra.launch import yaml as front

    if not hasattr(pyyaml, loader):
        pytest.skip(f"PyYAML built without {loader}")
    monkeypatch.setattr(front, "_LOADER", getattr(pyyaml, loader))
    root = parse("launch:\n  - param: {name: p, value: 1.10}\n  - rosparam:\n"
                 "      text: |\n        a: !degrees 90\n")
    assert root.children[0].location == Location("t.launch.yaml", 2, 5)
    assert root.children[0].get("value") == "1.10"
    assert root.children[1].text == "a: !degrees 90\n"
    err = error_of("launch:\n  - node: {pkg: p\n")
    assert err.message.startswith("invalid YAML") and err.location.line is not None
    assert "not allowed" in error_of("launch: [{param: !!python/name:os.system x}]\n").message


def _orchestra(*args):
    import subprocess
    import sys

    return subprocess.run([sys.executable, "-m", "orchestra", *args], capture_output=True,
                          text=True, timeout=60)


def test_orchestra_launch_reads_yaml_files():
    import json

    from conftest import REPO

    proc = _orchestra("launch", "--dump-plan", "--no-exec",
                      str(REPO / "launch" / "turtle_tf_demo.launch.yaml"))
    assert proc.returncode == 0, proc.stderr
    plan = json.loads(proc.stdout)
    assert [n["name"] for n in plan["nodes"]][:2] == ["sim", "teleop"]


def test_orchestra_launch_reports_bad_yaml_as_one_located_line(tmp_path):
    path = tmp_path / "bad.launch.yaml"
    path.write_text("launch:\n  - node: !!python/object:os.system {pkg: p}\n")
    proc = _orchestra("launch", "--dump-plan", "--no-exec", str(path))
    assert proc.returncode == 2
    assert proc.stderr.startswith(f"orchestra: error: {path}:2:11: YAML tag")
    assert "Traceback" not in proc.stderr


@pytest.mark.parametrize("loader", ["SafeLoader", "CSafeLoader"])
@pytest.mark.parametrize("char", ["\x01", "\x07", "\x7f", "\ufffe"])
def test_control_character_is_located_to_line_and_column(loader, char, monkeypatch):
    import yaml as pyyaml

    from orchestra.launch import yaml as front

    if not hasattr(pyyaml, loader):
        pytest.skip(f"PyYAML built without {loader}")
    monkeypatch.setattr(front, "_LOADER", getattr(pyyaml, loader))
    err = error_of(f'launch:\n  - arg: {{name: é€, default: "x{char}y"}}\n')
    assert err.location == Location("t.launch.yaml", 2, 32)
    assert "is not allowed" in err.message


def test_invalid_utf8_in_a_yaml_launch_file_is_located(tmp_path):
    path = tmp_path / "bad.launch.yaml"
    path.write_bytes(b"launch:\n  - arg: {name: a}\n  - arg: {name: b, default: x\xffy}\n")
    with pytest.raises(OrchestraError) as info:
        parse_file(str(path))
    assert info.value.location == Location(str(path), 3, 30)
    assert "0xff" in info.value.message
