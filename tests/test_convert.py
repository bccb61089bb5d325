"""``orchestra convert``: XML <-> YAML without changing what a launch file means."""
from __future__ import annotations

import json
import os
import re
import shutil
import subprocess
import sys

import pytest
from conftest import COMPAT, REPO

from orchestra.errors import OrchestraError
from orchestra.launch import convert
from orchestra.launch import xml as xml_frontend
from orchestra.launch import yaml as yaml_frontend
from orchestra.launch.entity import Entity

WS = COMPAT / "ws"
# the bundled demo, so these tests run without ../shared
DEMO = REPO / "packages" / "turtle_tf" / "launch" / "turtle_tf_demo.launch"
SMOKE = json.loads((COMPAT / "smoke.json").read_text()) if COMPAT.is_dir() else []
CASES = json.loads((COMPAT / "cases.json").read_text()) if COMPAT.is_dir() else []


def shape(entity: Entity):
    """What an Entity means, without where it was written (locations differ across files)."""
    entity = convert.without_layout(entity)

    def walk(e: Entity):
        return (e.tag, list(e.attributes.items()), e.text, [walk(c) for c in e.children])
    return walk(entity)


def run_cli(*args, env=None, cwd=None):
    return subprocess.run([sys.executable, "-m", "orchestra", *args], capture_output=True,
                          text=True, timeout=60, env=env, cwd=cwd)


# ------------------------------------------------------------------ the whole smoke corpus

@pytest.mark.parametrize("launch_file", [item["launch_file"] for item in SMOKE])
def test_xml_to_yaml_to_xml_round_trip_keeps_every_entity(launch_file, tmp_path):
    path = str(WS / launch_file)
    try:
        original = xml_frontend.parse_file(path)
    except OrchestraError:
        # not XML at all (a symlink flattened to its target's name): convert must refuse it
        # the same way, with an error instead of output
        with pytest.raises(OrchestraError):
            convert.convert_file(path, "yaml")
        return
    yaml_text = convert.to_yaml(original)
    from_yaml = yaml_frontend.parse_string(yaml_text, launch_file + ".yaml")
    assert shape(from_yaml) == shape(original)
    xml_text = convert.to_xml(from_yaml)
    back = xml_frontend.parse_string(xml_text, launch_file)
    assert shape(back) == shape(original)
    # and the output is stable: converting the converted file again changes nothing
    assert convert.to_yaml(from_yaml) == yaml_text
    assert convert.to_xml(back) == xml_text
    # the files, with their comments carried over, still read as the same Entities
    commented = tmp_path / "c.launch.yaml"
    commented.write_text(convert.convert_file(path, "yaml"))
    assert shape(yaml_frontend.parse_file(str(commented))) == shape(original)
    xml_again = convert.convert_file(str(commented), "xml")
    assert shape(xml_frontend.parse_string(xml_again, "x")) == shape(original)


def test_converted_yaml_keeps_line_numbers_meaningful():
    original = xml_frontend.parse_file(str(DEMO))
    yaml_text = convert.to_yaml(original)
    root = yaml_frontend.parse_string(yaml_text, "demo.launch.yaml")
    lines = yaml_text.splitlines()
    for child in root.children:
        assert lines[child.location.line - 1].strip().startswith(f"- {child.tag}:")


# ------------------------------------------- converted trees resolve to the same plans

@pytest.fixture(scope="module")
def yaml_ws(tmp_path_factory):
    """A copy of the compat workspace with every launch file converted to YAML beside it
    (``orchestra convert DIR --to yaml``: includes of converted files point at the YAML)."""
    root = tmp_path_factory.mktemp("yaml_ws") / "ws"
    shutil.copytree(WS, root, symlinks=True)
    for dirpath, _, _ in os.walk(root):
        os.chmod(dirpath, 0o755)  # the corpus is read-only; the copy must take new files
    env = dict(os.environ, ROS_PACKAGE_PATH=str(root))  # so $(find) names the copy
    proc = run_cli("convert", str(root), "--to", "yaml", env=env)
    assert proc.returncode == 0, proc.stderr
    converted = {}
    for line in proc.stdout.splitlines():
        source, _, target = line.partition(" -> ")
        converted[target] = source
    return root, converted


@pytest.fixture
def compat_env(monkeypatch, yaml_ws):
    """The corpus's environment convention: only PATH, ROS_PACKAGE_PATH and ROS_DISTRO."""
    for name in list(os.environ):
        if name not in ("PATH",):
            monkeypatch.delenv(name)
    monkeypatch.setenv("ROS_PACKAGE_PATH", str(yaml_ws[0]))
    monkeypatch.setenv("ROS_DISTRO", "noetic")
    return monkeypatch


def resolved(path: str, words: list[str], converted: dict[str, str]) -> str:
    """The plan (or the error) of ``path`` as JSON text, converted file names mapped back to
    their sources so that an XML tree and its YAML conversion can be compared."""
    from orchestra.launch.interpreter import binary_to_json, load_launch
    from orchestra.names import load_mappings

    try:
        plan = load_launch(path, load_mappings(words), no_exec=True)
        text = json.dumps(plan.to_json(), default=binary_to_json, sort_keys=True)
    except OrchestraError as exc:
        # same error, but lines and columns differ between a file and its conversion
        text = "error: " + re.sub(r"(\.\w+):\d+(?::\d+)?", r"\1", exc.message)
    for target in sorted(converted, key=len, reverse=True):
        text = text.replace(target, converted[target])
    return text


@pytest.mark.parametrize("case", CASES, ids=[c["id"] for c in CASES])
def test_compat_case_converted_to_yaml_resolves_to_the_same_plan(case, yaml_ws, compat_env):
    root, converted = yaml_ws
    for name, value in case["env"].items():
        compat_env.setenv(name, value)
    words = [f"{k}:={v}" for k, v in case["args"].items()]
    source = str(root / case["launch_file"])
    target = convert.target_name(source, "yaml")
    assert target in converted  # the top file and (below) its includes were converted
    from_xml = resolved(source, words, converted)
    from_yaml = resolved(target, words, converted)
    assert not from_xml.startswith("error"), from_xml
    assert from_yaml == from_xml
    loaded = json.loads(resolved(target, words, {}))["files_loaded"]
    assert loaded[0] == target
    # includes were pointed at the converted files, even $(arg)-built ones: all YAML
    assert [f for f in loaded if not f.endswith(".yaml")] == []


@pytest.mark.parametrize("launch_file", [item["launch_file"] for item in SMOKE])
def test_smoke_file_converted_to_yaml_resolves_or_fails_the_same(launch_file, yaml_ws,
                                                                 compat_env):
    root, converted = yaml_ws
    source = str(root / launch_file)
    target = convert.target_name(source, "yaml")
    assert target in converted
    from_yaml = resolved(target, [], converted)
    assert from_yaml == resolved(source, [], converted)
    if not from_yaml.startswith("error"):
        loaded = json.loads(resolved(target, [], {}))["files_loaded"]
        assert [f for f in loaded if not f.endswith(".yaml")] == []


# ---------------------------------------------------------------------- awkward strings

AWKWARD = ["", " lead", "trail ", "a: b", "#hash", "x #y", "[1, 2]", "{a: 1}", "yes", "~",
           "null", "1.10", "0o17", "'quoted'", '"dq"', "tab\there", "new\nline", "ünï",
           "- dash", "@at", "`tick", "$(arg a) $(find b)", "%percent", "a|b", "> gt", "*star",
           "&amp", "!bang", "<lt>", "a,b", "x" * 150, "multi  space"]


@pytest.mark.parametrize("value", AWKWARD)
def test_awkward_attribute_values_survive_both_directions(value):
    entity = Entity("launch", children=[Entity("param", {"name": "p", "value": value})])
    from_yaml = yaml_frontend.parse_string(convert.to_yaml(entity), "x.yaml")
    assert from_yaml.children[0].get("value") == value
    from_xml = xml_frontend.parse_string(convert.to_xml(entity), "x.launch")
    assert from_xml.children[0].get("value") == value


@pytest.mark.parametrize("text", [
    "\n    a: 1\n    b: [1, 2]\n  ",          # closing tag indented: trailing spaces
    "\n  a: 1\n",
    "a: 1",
    "  leading: indent\n",
    "x: !degrees 90\ny: !!binary aGk=\n",
    "\ta: tab\n",
    "a: 1\n\n\n",
])
def test_rosparam_text_survives_both_directions_exactly(text):
    entity = Entity("launch", children=[Entity("rosparam", {"command": "load"}, text=text)])
    yaml_text = convert.to_yaml(entity)
    assert yaml_frontend.parse_string(yaml_text, "x.yaml").children[0].text == text
    assert xml_frontend.parse_string(convert.to_xml(entity), "x").children[0].text == text


COMMENTED_XML = """<?xml version="1.0"?>
<!-- Demo launch file.
     Two lines of header. -->
<launch>
  <!-- the robot's name -->
  <arg name="robot" default="r1"/>
  <group ns="$(arg robot)">
    <!-- first -->
    <!-- second -->
    <node pkg="p" type="t" name="n"/>
  </group>
  <param name="x" value="1"/>  <!-- trailing: not before an element of its own -->
</launch>
"""


def test_comments_before_elements_travel_to_yaml_and_back(tmp_path):
    src = tmp_path / "a.launch"
    src.write_text(COMMENTED_XML)
    yaml_text = convert.convert_file(str(src), "yaml")
    assert yaml_text.splitlines()[:5] == [
        "# Demo launch file.", "# Two lines of header.", "launch:",
        "  # the robot's name", "  - arg: {name: robot, default: r1}"]
    assert "        # first\n        # second\n        - node:" in yaml_text
    converted = tmp_path / "a.launch.yaml"
    converted.write_text(yaml_text)
    xml_text = convert.convert_file(str(converted), "xml")
    assert "<!-- the robot's name -->\n  <arg" in xml_text
    # YAML has no boundary between comment lines: two comments come back as one
    assert "<!--\n      first\n      second\n    -->\n    <node" in xml_text
    assert xml_text.index("Two lines of header.") < xml_text.index("<launch>")
    assert shape(xml_frontend.parse_string(xml_text, "b")) == \
        shape(xml_frontend.parse_file(str(src)))


def test_comment_that_xml_cannot_hold_is_made_valid():
    entity = Entity("launch", children=[Entity("arg", {"name": "a"})])
    xml_text = convert.to_xml(entity, {id(entity.children[0]): ["a -- b -"]})
    assert "<!-- a - - b - -->" in xml_text
    assert shape(xml_frontend.parse_string(xml_text, "x")) == shape(entity)


def test_multiline_rosparam_text_is_written_as_a_literal_block():
    entity = Entity("launch", children=[Entity("rosparam", {}, text="\n  a: 1\n  b: 2\n")])
    assert "text: |" in convert.to_yaml(entity)


def test_leaf_elements_are_written_on_one_line():
    entity = Entity("launch", children=[Entity("arg", {"name": "a", "default": "true"})])
    assert convert.to_yaml(entity) == "launch:\n  - arg: {name: a, default: true}\n"


def test_reserved_attribute_name_cannot_be_written_as_yaml():
    entity = Entity("launch", children=[Entity("node", {"children": "x"})])
    with pytest.raises(OrchestraError, match="reserves"):
        convert.to_yaml(entity)


@pytest.mark.parametrize("entity", [
    Entity("launch", children=[Entity("rosparam", text="a: \x01")]),
    Entity("launch", children=[Entity("param", {"value": "\x02"})]),
    Entity("launch", children=[Entity("param", {"my attr": "x"})]),
    Entity("launch", children=[Entity("1tag")]),
])
def test_what_xml_cannot_hold_is_a_located_error(entity):
    with pytest.raises(OrchestraError, match="cannot be written as XML|not a valid XML"):
        convert.to_xml(entity)


def test_yaml_aliases_are_written_back_with_roslaunch_names(tmp_path):
    src = tmp_path / "a.launch.yaml"
    src.write_text("launch:\n  - node: {pkg: p, exec: t, namespace: n}\n")
    xml_text = convert.convert_file(str(src), "xml")
    node = xml_frontend.parse_string(xml_text, "a.launch").children[0]
    assert node.attributes == {"pkg": "p", "type": "t", "ns": "n"}


# ------------------------------------------------------------------------------ the CLI

def test_cli_convert_file_prints_yaml_that_reads_back_the_same():
    path = DEMO
    proc = run_cli("convert", str(path), "--to", "yaml")
    assert proc.returncode == 0, proc.stderr
    assert shape(yaml_frontend.parse_string(proc.stdout, "x.yaml")) == \
        shape(xml_frontend.parse_file(str(path)))


def test_cli_convert_writes_output_file(tmp_path):
    src = tmp_path / "a.launch.yaml"
    src.write_text("launch:\n  - arg: {name: a, default: 1}\n")
    out = tmp_path / "a.launch"
    proc = run_cli("convert", str(src), "--to", "xml", "-o", str(out))
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout == ""
    assert xml_frontend.parse_file(str(out)).children[0].attributes == {"name": "a",
                                                                        "default": "1"}


def test_cli_convert_bad_input_is_one_located_error_line(tmp_path):
    src = tmp_path / "bad.launch.yaml"
    src.write_text("launch:\n  - node: {pkg: p\n")
    proc = run_cli("convert", str(src), "--to", "xml")
    assert proc.returncode == 2
    assert "Traceback" not in proc.stderr
    assert f"{src}:" in proc.stderr and "invalid YAML" in proc.stderr


def test_cli_convert_directory_rewrites_includes_of_converted_files(tmp_path):
    pkg = tmp_path / "pkg" / "launch"
    pkg.mkdir(parents=True)
    (pkg / "top.launch").write_text(
        '<launch>\n  <include file="$(dirname)/inner.launch"/>\n'
        '  <include file="$(find other)/launch/outside.launch"/>\n</launch>\n')
    (pkg / "inner.launch").write_text('<launch><arg name="x" default="1"/></launch>\n')
    (tmp_path / "pkg" / "package.xml").write_text("<package><name>pkg</name></package>\n")
    proc = run_cli("convert", str(tmp_path / "pkg"), "--to", "yaml")
    assert proc.returncode == 0, proc.stderr
    top = yaml_frontend.parse_file(str(pkg / "top.launch.yaml"))
    assert [c.get("file") for c in top.children] == [
        "$(dirname)/inner.launch.yaml",               # converted in the same run
        "$(find other)/launch/outside.launch"]        # not ours: left as written
    assert (pkg / "inner.launch.yaml").is_file()
    assert not (tmp_path / "pkg" / "package.xml.yaml").exists()
    assert (pkg / "top.launch").is_file()  # sources are kept


def test_directory_conversion_rewrites_arg_built_includes_only_when_all_candidates_convert(
        tmp_path, monkeypatch):
    ws = tmp_path / "ws"
    for pkg in ("robot", "other"):
        (ws / pkg / "launch" / "bases" / "a").mkdir(parents=True)
        (ws / pkg / "package.xml").write_text(f"<package><name>{pkg}</name></package>\n")
    launch = ws / "robot" / "launch"
    (launch / "bases" / "a" / "base.launch.xml").write_text("<launch/>\n")
    (launch / "common.launch").write_text("<launch/>\n")
    (ws / "other" / "launch" / "common.launch").write_text("<launch/>\n")
    (launch / "top.launch").write_text(
        '<launch>\n'
        '  <include file="$(find robot)/launch/bases/$(arg base)/base.launch.xml"/>\n'
        '  <include file="$(find other)/launch/common.launch"/>\n'
        '  <include file="$(dirname)/common.launch"/>\n'
        '  <include file="$(arg anywhere)/common.launch"/>\n</launch>\n')
    monkeypatch.setenv("ROS_PACKAGE_PATH", str(ws))
    convert.convert_tree(str(ws / "robot"), "yaml")
    top = yaml_frontend.parse_file(str(launch / "top.launch.yaml"))
    assert [c.get("file") for c in top.children] == [
        "$(find robot)/launch/bases/$(arg base)/base.launch.xml.yaml",  # every base converted
        "$(find other)/launch/common.launch",   # same name, but outside the converted tree
        "$(dirname)/common.launch.yaml",
        "$(arg anywhere)/common.launch"]        # could be anywhere: left as written


def test_directory_conversion_writes_nothing_when_one_file_is_bad(tmp_path):
    (tmp_path / "a.launch").write_text("<launch/>\n")
    (tmp_path / "b.launch").write_text("<launch>\n")
    with pytest.raises(OrchestraError):
        convert.convert_tree(str(tmp_path), "yaml")
    assert sorted(os.listdir(tmp_path)) == ["a.launch", "b.launch"]


def test_target_names_pair_up():
    assert convert.target_name("d/x.launch", "yaml") == "d/x.launch.yaml"
    assert convert.target_name("d/x.launch.xml", "yaml") == "d/x.launch.xml.yaml"
    assert convert.target_name("d/x.launch.xml.yaml", "xml") == "d/x.launch.xml"
    assert convert.target_name("d/x.launch.yaml", "xml") == "d/x.launch"
    assert convert.target_name("d/x.yml", "xml") == "d/x.launch"


def test_empty_attribute_is_written_as_an_empty_string_not_a_tagged_null():
    entity = Entity("launch", children=[Entity("arg", {"name": "x", "default": ""})])
    text = convert.to_yaml(entity)
    assert "default: ''" in text and "!!null" not in text
    assert yaml_frontend.parse_string(text, "x.yaml").children[0].get("default") == ""
