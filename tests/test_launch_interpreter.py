"""Tag rules of the interpreter, on small launch files written for each behaviour."""
import os
import re
import sys

import pytest

from orchestra.errors import OrchestraError
from orchestra.launch.interpreter import load_launch


@pytest.fixture
def write(tmp_path):
    def _write(name, text):
        path = tmp_path / name
        path.write_text(text)
        return str(path)
    return _write


def launch(write, text, args=None, **kw):
    return load_launch(write("main.launch", f"<launch>{text}</launch>"), args, **kw)


def test_param_type_inference_matches_roslaunch(write):
    plan = launch(write, '<param name="i" value="2"/><param name="f" value="2.0"/>'
                         '<param name="b" value="True"/><param name="s" value="1e5"/>'
                         '<param name="forced" value="10" type="str"/>'
                         '<param name="y" type="yaml" value="{a: [1, 2]}"/>')
    assert plan.params == {"/i": 2, "/f": 2.0, "/b": True, "/s": "1e5", "/forced": "10",
                           "/y": {"a": [1, 2]}}


def test_duplicate_param_last_one_wins(write):
    plan = launch(write, '<param name="p" value="1"/><param name="p" value="2"/>')
    assert plan.params["/p"] == 2


def test_group_remap_applies_to_nested_include(write):
    write("inc.launch", '<launch><node name="n" pkg="p" type="t"/></launch>')
    plan = launch(write, '<group ns="g"><remap from="a" to="b"/>'
                         '<include file="$(dirname)/inc.launch"/></group>')
    node = plan.nodes[0]
    assert (node.namespace, node.remap_args) == ("/g/", (("a", "b"),))


def test_node_remap_replaces_inherited_remap_with_same_from(write):
    plan = launch(write, '<remap from="x" to="outer"/><remap from="y" to="kept"/>'
                         '<node name="n" pkg="p" type="t"><remap from="x" to="inner"/></node>')
    assert plan.nodes[0].remap_args == (("y", "kept"), ("x", "inner"))


def test_args_declared_in_a_group_do_not_leak_out(write):
    with pytest.raises(OrchestraError, match="'inner'"):
        launch(write, '<group><arg name="inner" value="1"/></group>'
                      '<param name="p" value="$(arg inner)"/>')


def test_command_line_arg_overrides_default_but_not_value(write):
    text = '<arg name="d" default="x"/><param name="p" value="$(arg d)"/>'
    assert launch(write, text, {"d": "cli"}).params["/p"] == "cli"
    with pytest.raises(OrchestraError, match="override"):
        launch(write, '<arg name="v" value="x"/>', {"v": "cli"})


def test_pass_all_args_reaches_the_included_file(write):
    write("inc.launch", '<launch><arg name="a"/><param name="got" value="$(arg a)"/></launch>')
    plan = launch(write, '<arg name="a" default="42"/>'
                         '<include file="$(dirname)/inc.launch" pass_all_args="true"/>')
    assert plan.params["/got"] == 42


def test_arg_passed_to_include_must_be_declared_there(write):
    write("inc.launch", "<launch/>")
    with pytest.raises(OrchestraError, match="unused args"):
        launch(write, '<include file="$(dirname)/inc.launch"><arg name="x" value="1"/></include>')


def test_include_cycle_is_a_clear_error(write):
    write("a.launch", '<launch><include file="$(dirname)/b.launch"/></launch>')
    write("b.launch", '<launch><include file="$(dirname)/a.launch"/></launch>')
    with pytest.raises(OrchestraError, match="include cycle"):
        load_launch(write("top.launch", '<launch><include file="$(dirname)/a.launch"/></launch>'))


def test_missing_include_names_the_include_line(write):
    with pytest.raises(OrchestraError) as info:
        launch(write, '\n<include file="/does/not/exist.launch"/>')
    assert "main.launch:2" in str(info.value) and "does not exist" in str(info.value)


@pytest.mark.parametrize("target", ["missing.launch", "missing.launch.yaml", "a_directory",
                                    "a_fifo"])
def test_include_of_what_is_not_a_file_names_the_include_line(write, tmp_path, target):
    (tmp_path / "a_directory").mkdir()
    os.mkfifo(tmp_path / "a_fifo")
    with pytest.raises(OrchestraError) as info:
        launch(write, f'\n<include file="{tmp_path / target}"/>')
    assert str(info.value).startswith(f"{tmp_path / 'main.launch'}:2: <include> ")
    assert f"included file does not exist: [{tmp_path / target}]" in str(info.value)


def test_include_of_a_broken_file_gives_the_files_own_error(write):
    write("bad.launch", "<launch><node")
    with pytest.raises(OrchestraError, match="invalid XML") as info:
        launch(write, '<include file="$(dirname)/bad.launch"/>')
    assert "bad.launch:1" in str(info.value)


def test_private_params_apply_to_later_nodes_in_scope(write):
    plan = launch(write, '<param name="~rate" value="5"/>'
                         '<group ns="g"><node name="a" pkg="p" type="t">'
                         '<param name="own" value="x"/></node></group>')
    assert plan.params == {"/g/a/rate": 5, "/g/a/own": "x"}


def test_rosparam_dicts_flatten_and_subst_value(write):
    plan = launch(write, '<arg name="v" value="7"/><group ns="ns">'
                         '<rosparam subst_value="true">a: {b: $(arg v), c: [1]}</rosparam>'
                         '<rosparam param="lst">[1, 2]</rosparam></group>')
    assert plan.params == {"/ns/a/b": 7, "/ns/a/c": [1], "/ns/lst": [1, 2]}


def test_clear_params_needs_ns_on_group_and_records_node_ns(write):
    plan = launch(write, '<group ns="g" clear_params="true"><node name="n" pkg="p" type="t" '
                         'clear_params="true"/></group>')
    assert plan.clear_params == ("/g/", "/g/n/")
    with pytest.raises(OrchestraError, match="clear_params"):
        launch(write, '<group clear_params="true"/>')


def test_env_is_inherited_by_nodes_and_include_env_by_included_nodes(write):
    write("inc.launch", '<launch><node name="i" pkg="p" type="t"/></launch>')
    plan = launch(write, '<env name="A" value="1"/><include file="$(dirname)/inc.launch">'
                         '<env name="B" value="2"/></include><node name="n" pkg="p" type="t"/>')
    assert plan.nodes[0].env_args == (("A", "1"), ("B", "2"))
    assert plan.nodes[1].env_args == (("A", "1"),)


def test_if_unless_on_every_tag_and_both_is_an_error(write):
    plan = launch(write, '<param name="a" value="1" if="true"/><param name="b" value="1" '
                         'unless="1"/><node name="n" pkg="p" type="t" if="0"/>')
    assert plan.params == {"/a": 1} and plan.nodes == ()
    with pytest.raises(OrchestraError, match="both"):
        launch(write, '<param name="a" value="1" if="1" unless="0"/>')


def test_machine_default_applies_to_later_nodes(write, monkeypatch):
    monkeypatch.setenv("ROS_DISTRO", "noetic")
    plan = launch(write, '<node name="before" pkg="p" type="t"/>'
                         '<machine name="m" address="host" default="true"/>'
                         '<node name="after" pkg="p" type="t"/>')
    assert [n.machine_name for n in plan.nodes] == [None, "m"]
    assert plan.machines["m"].env_loader == "/opt/ros/noetic/env.sh"
    assert "" in plan.machines


def test_command_param_runs_at_load_time_unless_no_exec(write):
    cmd = f"{sys.executable} -c \"print(41 + 1)\""
    text = f"<param name=\"c\" command='{cmd}' type=\"int\"/>"
    assert launch(write, text).params["/c"] == 42
    assert launch(write, text, no_exec=True).params["/c"] == {"__command__": cmd}


def test_failing_command_param_is_an_error(write):
    with pytest.raises(OrchestraError, match="exit code"):
        launch(write, f'<param name="c" command="{sys.executable} -c \'raise SystemExit(3)\'"/>')


def test_test_tag_fields(write):
    plan = launch(write, '<test test-name="t1" pkg="p" type="t" time-limit="5" retry="2"/>')
    test = plan.tests[0]
    assert (test.name, test.test_name, test.time_limit, test.retry, test.output) == \
        ("t1", "t1", 5.0, 2, "log")


@pytest.mark.parametrize("text, attr", [
    ('<node name="n" pkg="p" type="t" respawn="maybe"/>', "respawn"),
    ('<node pkg="p" type="t"/>', "name"),
    ('<node name="a/b" pkg="p" type="t"/>', "name"),
    ('<param name="p"/>', "value"),
    ('<test test-name="t" pkg="p" type="t" output="screen"/>', "output"),
    ('<machine name="m" address="a" timeout="-1"/>', "timeout"),
    ('<remap from="a b" to="c"/>', "a b"),
])
def test_rejections_name_file_line_and_attribute(write, text, attr):
    with pytest.raises(OrchestraError) as info:
        launch(write, "\n" + text)
    message = str(info.value)
    assert "main.launch:2" in message and attr in message


def test_duplicate_node_names_are_rejected(write):
    with pytest.raises(OrchestraError, match="duplicate node name"):
        launch(write, '<node name="n" pkg="p" type="t"/><node name="n" pkg="q" type="t"/>')


@pytest.mark.parametrize("text, attr", [
    ('<group ns="~x"/>', "ns"),
    ('<node name="~a" pkg="p" type="t"/>', "name"),
    ('<param name="y" type="yaml" value="[1, 2"/>', "value"),
])
def test_private_namespaces_and_bad_yaml_values_are_located_errors(write, text, attr):
    with pytest.raises(OrchestraError) as info:
        launch(write, "\n" + text)
    assert "main.launch:2" in str(info.value) and attr in str(info.value)


def test_yaml_launch_file_uses_the_same_rules_and_can_include_xml(write):
    write("inc.launch", '<launch><arg name="who"/><node name="x" pkg="p" type="t" '
                        'args="$(arg who)"/></launch>')
    path = write("main.launch.yaml", "launch:\n"
                 "  - arg: {name: rate, default: '10'}\n"
                 "  - group:\n"
                 "      ns: g\n"
                 "      children:\n"
                 "        - param: {name: rate, value: $(arg rate)}\n"
                 "        - include:\n"
                 "            file: $(dirname)/inc.launch\n"
                 "            children: [{arg: {name: who, value: me}}]\n")
    plan = load_launch(path, {"rate": "5"})
    assert plan.params == {"/g/rate": 5}
    assert [(n.full_name, n.args) for n in plan.nodes] == [("/g/x", "me")]
    assert plan.files_loaded == (path, path.replace("main.launch.yaml", "inc.launch"))


def test_error_in_included_file_keeps_its_location_and_names_the_include(write):
    write("inc.launch", '<launch>\n<node name="n" pkg="p" type="t" respawn="x"/></launch>')
    with pytest.raises(OrchestraError) as info:
        launch(write, '\n\n<include file="$(dirname)/inc.launch"/>')
    assert info.value.location.file.endswith("inc.launch") and info.value.location.line == 2
    assert "included from" in str(info.value) and "main.launch:3" in str(info.value)


def test_output_both_is_accepted_and_other_modes_are_refused(write):
    plan = launch(write, '<node name="n" pkg="p" type="t" output="both"/>')
    assert plan.nodes[0].output == "both"
    with pytest.raises(OrchestraError, match="'log', 'screen', 'both'"):
        launch(write, '<node name="n" pkg="p" type="t" output="loud"/>')


def test_include_chain_deeper_than_the_bound_is_a_located_error(write):
    from orchestra.launch.interpreter import MAX_INCLUDE_DEPTH
    depth = MAX_INCLUDE_DEPTH + 20
    for i in range(depth):
        write(f"f{i}.launch", f'<launch><include file="$(dirname)/f{i + 1}.launch"/></launch>')
    write(f"f{depth}.launch", "<launch/>")
    with pytest.raises(OrchestraError, match=f"more than {MAX_INCLUDE_DEPTH} files deep") as info:
        load_launch(write("main.launch", '<launch><include file="$(dirname)/f0.launch"/>'
                                         '</launch>'))
    assert info.value.location.line == 1
    from orchestra.errors import MAX_MESSAGE
    assert len(info.value.message) <= MAX_MESSAGE + len("... (100000 chars)")


@pytest.mark.parametrize("element", [
    '<node name="n" pkg="p" type="t" respawn="{v}"/>',
    '<node name="n" pkg="p" type="t" respawn_delay="{v}"/>',
    '<param name="p" type="int" value="{v}"/>',
])
def test_a_huge_value_is_clipped_in_the_error_with_its_length(write, element):
    huge = "x" * 2**20
    with pytest.raises(OrchestraError) as info:
        launch(write, element.format(v=huge))
    text = str(info.value)
    assert len(text) < 600 and re.search(r"\.\.\. \(10485\d\d chars\)", text)
    assert info.value.location.line == 1


def test_clip_keeps_short_text_and_notes_the_length_of_long_text():
    from orchestra.errors import clip
    assert clip("short") == "short"
    assert clip("y" * 1000, 10) == "yyyyyyyyyy... (1000 chars)"
