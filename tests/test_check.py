"""``orchestra check``: every problem, located to the column, nothing run."""
from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from orchestra.launch.check import ERROR, WARNING, check_files


@pytest.fixture
def ws(tmp_path, monkeypatch):
    """A workspace with one package, ``mypkg``, on ROS_PACKAGE_PATH."""
    pkg = tmp_path / "ws" / "mypkg"
    (pkg / "launch").mkdir(parents=True)
    (pkg / "config").mkdir()
    (pkg / "package.xml").write_text("<package><name>mypkg</name></package>\n")
    (pkg / "config" / "gains.yaml").write_text("p: 1.0\n")
    (pkg / "scripts").mkdir()
    for exe in ("t", "x", "y"):
        (pkg / "scripts" / exe).write_text("#!/bin/sh\n")
        (pkg / "scripts" / exe).chmod(0o755)
    monkeypatch.setenv("ROS_PACKAGE_PATH", str(tmp_path / "ws"))
    return pkg


def write(directory: Path, name: str, text: str) -> str:
    path = directory / name
    path.write_text(text)
    return str(path)


def codes(report, severity=None):
    return sorted(p.code for p in report.problems
                  if severity is None or p.severity == severity)


def only(report, code):
    found = [p for p in report.problems if p.code == code]
    assert len(found) == 1, [str(p) for p in report.problems]
    return found[0]


def test_clean_file_has_no_problems(ws):
    path = write(ws / "launch", "ok.launch",
                 '<launch>\n  <arg name="rate" default="10"/>\n'
                 '  <node pkg="mypkg" type="t" name="n" args="$(arg rate)">\n'
                 '    <rosparam file="$(find mypkg)/config/gains.yaml" command="load"/>\n'
                 '  </node>\n</launch>\n')
    assert check_files([path]).problems == []


def test_unknown_tag_is_an_error_with_line_and_column(ws):
    path = write(ws / "launch", "a.launch", '<launch>\n  <nod pkg="mypkg" type="t" name="n"/>\n'
                 '</launch>\n')
    problem = only(check_files([path]), "unknown-tag")
    assert problem.severity == ERROR
    assert (problem.location.file, problem.location.line, problem.location.column) == \
        (path, 2, 3)
    assert "did you mean 'node'" in problem.message


def test_tag_in_the_wrong_parent_is_reported(ws):
    path = write(ws / "launch", "a.launch", '<launch>\n  <include file="$(dirname)/b.launch">'
                 '\n    <param name="p" value="1"/>\n  </include>\n</launch>\n')
    write(ws / "launch", "b.launch", "<launch/>\n")
    problem = only(check_files([path]), "unknown-tag")
    assert "<param> is not allowed inside <include>" in problem.message
    assert problem.location.line == 3


def test_unknown_attribute_is_a_warning_pointing_at_the_attribute(ws):
    path = write(ws / "launch", "a.launch",
                 '<launch>\n  <node pkg="mypkg" type="t" name="n"\n        respwan="true"/>\n'
                 '</launch>\n')
    problem = only(check_files([path]), "unknown-attribute")
    assert problem.severity == WARNING
    assert (problem.location.line, problem.location.column) == (3, 9)
    assert "did you mean 'respawn'" in problem.message


def test_undeclared_arg_is_an_error_unless_given_on_the_command_line(ws):
    path = write(ws / "launch", "a.launch",
                 '<launch>\n  <param name="p" value="$(arg speed)"/>\n</launch>\n')
    problem = only(check_files([path]), "undeclared-arg")
    assert problem.severity == ERROR and "'speed'" in problem.message
    assert (problem.location.line, problem.location.column) == (2, 19)
    assert "undeclared-arg" not in codes(check_files([path], {"speed": "2"}))


def test_args_read_by_eval_count_as_used_and_declared(ws):
    path = write(ws / "launch", "a.launch",
                 '<launch>\n  <arg name="a" default="1"/>\n  <arg name="b" default="2"/>\n'
                 '  <param name="p" value="$(eval a + arg(\'b\') + c)"/>\n</launch>\n')
    report = check_files([path])
    assert "unused-arg" not in codes(report)
    assert "'c'" in only(report, "undeclared-arg").message


def test_args_handed_in_by_pass_all_args_need_no_declaration(ws):
    write(ws / "launch", "inner.launch",
          '<launch>\n  <param name="p" value="$(arg rate)"/>\n</launch>\n')
    path = write(ws / "launch", "a.launch", '<launch>\n  <arg name="rate" default="1"/>\n'
                 '  <include file="$(dirname)/inner.launch" pass_all_args="true"/>\n</launch>\n')
    assert check_files([path]).problems == []


def test_unused_arg_is_a_warning(ws):
    path = write(ws / "launch", "a.launch",
                 '<launch>\n  <arg name="used" default="1"/>\n  <arg name="idle" default="2"/>\n'
                 '  <param name="p" value="$(arg used)"/>\n</launch>\n')
    problem = only(check_files([path]), "unused-arg")
    assert problem.severity == WARNING and "'idle'" in problem.message
    assert problem.location.line == 3


def test_pass_all_args_makes_every_arg_used(ws):
    write(ws / "launch", "inner.launch", '<launch>\n  <arg name="x"/>\n'
          '  <param name="p" value="$(arg x)"/>\n</launch>\n')
    path = write(ws / "launch", "a.launch", '<launch>\n  <arg name="x" default="1"/>\n'
                 '  <include file="$(dirname)/inner.launch" pass_all_args="true"/>\n</launch>\n')
    assert check_files([path]).problems == []


def test_missing_package_is_an_error_in_a_taken_branch_and_a_warning_otherwise(ws):
    path = write(ws / "launch", "a.launch",
                 '<launch>\n  <arg name="sim" default="false"/>\n'
                 '  <node pkg="nopkg" type="t" name="a"/>\n'
                 '  <include if="$(arg sim)" file="$(find gazebo_nowhere)/x.launch"/>\n'
                 '</launch>\n')
    report = check_files([path])
    by_line = {p.location.line: p for p in report.problems
               if p.code in ("missing-package", "missing-node")}
    assert by_line[3].severity == ERROR and "'nopkg'" in by_line[3].message
    assert by_line[4].severity == WARNING and "not take" in by_line[4].message
    assert report.errors  # the node's package really is missing
    with_sim = check_files([path], {"sim": "true"})
    assert [p.severity for p in with_sim.problems
            if p.code == "missing-package" and p.location.line == 4] == [ERROR]


def test_node_executable_that_the_package_lacks_is_reported(ws):
    path = write(ws / "launch", "a.launch",
                 '<launch>\n  <node pkg="mypkg" type="nonexistent" name="n"/>\n</launch>\n')
    problem = only(check_files([path]), "missing-node")
    assert problem.severity == ERROR and "nonexistent" in problem.message
    assert (problem.location.line, problem.location.column) == (2, 21)


def test_substitution_that_can_never_resolve_is_reported_in_every_branch(ws):
    path = write(ws / "launch", "a.launch",
                 '<launch>\n  <param name="a" value="$(fnd mypkg)"/>\n'
                 '  <group if="false">\n    <param name="b" value="$(arg)"/>\n'
                 '    <param name="c" value="$(eval 1 +)"/>\n  </group>\n</launch>\n')
    report = check_files([path])
    found = {p.location.line: p for p in report.problems if p.code == "bad-substitution"}
    assert sorted(found) == [2, 4, 5]
    assert found[2].severity == ERROR and "did you mean 'find'" in found[2].message
    assert found[4].severity == WARNING and "takes 1 argument" in found[4].message
    assert "not a valid expression" in found[5].message


def test_missing_required_attribute_in_an_untaken_branch_is_a_warning(ws):
    path = write(ws / "launch", "a.launch",
                 '<launch>\n  <group if="false">\n    <node pkg="mypkg" type="t"/>\n'
                 '  </group>\n</launch>\n')
    problem = only(check_files([path]), "missing-attribute")
    assert problem.severity == WARNING and "'name'" in problem.message


def test_missing_rosparam_and_textfile_files_are_reported(ws):
    path = write(ws / "launch", "a.launch",
                 '<launch>\n  <rosparam command="load" file="$(find mypkg)/config/none.yaml"/>\n'
                 '  <param name="t" textfile="$(dirname)/missing.txt"/>\n'
                 '  <rosparam command="dump" file="$(dirname)/written_later.yaml"/>\n'
                 '</launch>\n')
    report = check_files([path])
    missing = sorted((p.location.line, p.location.column) for p in report.problems
                     if p.code == "missing-file")
    assert missing == [(2, 28), (3, 19)]


def test_include_cycle_is_reported_once_with_the_chain(ws):
    a = write(ws / "launch", "a.launch",
              '<launch>\n  <include file="$(dirname)/b.launch"/>\n</launch>\n')
    write(ws / "launch", "b.launch",
          '<launch>\n  <include file="$(find mypkg)/launch/a.launch"/>\n</launch>\n')
    report = check_files([a])
    cycle = only(report, "include-cycle")
    assert cycle.severity == ERROR
    assert "a.launch -> b.launch -> a.launch" in cycle.message


def test_duplicate_node_names_are_reported_from_the_resolved_plan(ws):
    path = write(ws / "launch", "a.launch",
                 '<launch>\n  <group ns="g">\n    <node pkg="mypkg" type="t" name="n"/>\n'
                 '  </group>\n  <node pkg="mypkg" type="t" name="n" ns="g"/>\n</launch>\n')
    report = check_files([path])
    [problem] = report.errors
    assert "duplicate node name [/g/n]" in problem.message
    assert problem.location.line == 5


def test_duplicate_test_names_are_reported_too(ws):
    path = write(ws / "launch", "a.test",
                 '<launch>\n  <test test-name="t" pkg="mypkg" type="x"/>\n'
                 '  <test test-name="t" pkg="mypkg" type="y"/>\n</launch>\n')
    problem = only(check_files([path]), "duplicate-node")
    assert problem.location.line == 3 and "/t" in problem.message


def test_respawn_with_required_is_an_error(ws):
    path = write(ws / "launch", "a.launch",
                 '<launch>\n  <node pkg="mypkg" type="t" name="n" respawn="true" '
                 'required="true"/>\n</launch>\n')
    problem = only(check_files([path]), "respawn-required")
    assert problem.severity == ERROR
    assert problem.location.column == 54


def test_every_problem_is_reported_not_only_the_first(ws):
    path = write(ws / "launch", "a.launch",
                 '<launch>\n'
                 '  <param name="a" value="$(arg nope)"/>\n'            # undeclared arg
                 '  <node pkg="mypkg" type="t" name="n" output="loud"/>\n'  # bad value
                 '  <rosparam file="$(dirname)/none.yaml"/>\n'           # missing file
                 '  <param name="b"/>\n'                                 # no value
                 '</launch>\n')
    report = check_files([path])
    assert sorted(p.location.line for p in report.errors) == [2, 3, 4, 5]


def test_problems_inside_included_files_carry_their_own_file(ws):
    write(ws / "launch", "inner.launch",
          '<launch>\n  <node pkg="mypkg" type="t" name="n" output="loud"/>\n</launch>\n')
    path = write(ws / "launch", "a.launch",
                 '<launch>\n  <include file="$(dirname)/inner.launch"/>\n</launch>\n')
    [problem] = check_files([path]).errors
    assert problem.location.file.endswith("inner.launch")
    assert problem.location.line == 2 and "output" in problem.message


def test_yaml_launch_files_are_checked_with_yaml_columns(ws):
    path = write(ws / "launch", "a.launch.yaml",
                 "launch:\n  - node: {pkg: mypkg, type: t, name: n, respwan: 'true'}\n")
    problem = only(check_files([path]), "unknown-attribute")
    assert (problem.location.line, problem.location.column) == (2, 42)


def test_yaml_conversion_has_the_same_problems_as_the_xml(ws):
    from orchestra.launch.convert import convert_file

    xml_path = write(ws / "launch", "a.launch",
                     '<launch>\n  <arg name="idle" default="1"/>\n'
                     '  <node pkg="nopkg" type="t" name="n" respawn="true" required="true"/>\n'
                     '  <param name="a" value="$(arg nope)"/>\n  <nod/>\n</launch>\n')
    yaml_path = write(ws / "launch", "a.launch.yaml", convert_file(xml_path, "yaml"))
    assert codes(check_files([yaml_path])) == codes(check_files([xml_path]))
    assert codes(check_files([xml_path])) == ["missing-node", "respawn-required",
                                              "undeclared-arg", "unknown-tag", "unused-arg"]


def test_syntax_error_is_one_located_problem(ws):
    path = write(ws / "launch", "a.launch", "<launch>\n  <node\n</launch>\n")
    [problem] = check_files([path]).problems
    assert problem.code == "syntax" and problem.location.file == path


def test_command_params_are_not_run(ws, tmp_path):
    marker = tmp_path / "ran"
    path = write(ws / "launch", "a.launch",
                 f'<launch>\n  <param name="p" command="touch {marker}"/>\n</launch>\n')
    assert check_files([path]).problems == []
    assert not marker.exists()


# ---------------------------------------------------------------------------------- CLI

def run_cli(*args, env=None):
    return subprocess.run([sys.executable, "-m", "orchestra", "check", *args],
                          capture_output=True, text=True, timeout=60, env=env)


def test_cli_exit_status_and_line_format(ws):
    bad = write(ws / "launch", "bad.launch",
                '<launch>\n  <param name="p" value="$(arg nope)"/>\n</launch>\n')
    warn = write(ws / "launch", "warn.launch",
                 '<launch>\n  <arg name="idle" default="1"/>\n</launch>\n')
    env = dict(os.environ)
    proc = run_cli(bad, env=env)
    assert proc.returncode == 2
    assert proc.stdout.startswith(f"{bad}:2:19: error: arg 'nope'")
    assert "Traceback" not in proc.stderr
    assert run_cli(warn, env=env).returncode == 0
    assert run_cli(warn, "--strict", env=env).returncode == 2
    assert run_cli(bad, "nope:=1", env=env).returncode == 0


def test_cli_json_output_lists_problems_with_positions(ws):
    path = write(ws / "launch", "a.launch", '<launch>\n  <nod/>\n</launch>\n')
    proc = run_cli(path, "--json", env=dict(os.environ))
    assert proc.returncode == 2
    document = json.loads(proc.stdout)
    assert document["problems"] == [{
        "file": path, "line": 2, "column": 3, "severity": "error", "code": "unknown-tag",
        "message": "unknown tag <nod> (did you mean 'node'?) (roslaunch ignores it)"}]


def test_cli_missing_file_is_reported_not_a_traceback(tmp_path):
    proc = run_cli(str(tmp_path / "none.launch"))
    assert proc.returncode == 2
    assert "launch file not found" in proc.stdout
    assert "Traceback" not in proc.stderr


# ------------------------------------------------------------------------- the corpus

@pytest.mark.timeout(120)
def test_check_flags_every_smoke_file_roslaunch_rejects(compat_dir, monkeypatch):
    """Each of the smoke files roslaunch refuses gets at least one error from check; the
    files it loads get none except missing node packages/executables (the corpus ships no
    code)."""
    monkeypatch.setenv("ROS_PACKAGE_PATH", str(compat_dir / "ws"))
    monkeypatch.setenv("ROS_DISTRO", "noetic")
    for var in ("ROS_NAMESPACE", "HOME", "DISPLAY"):
        monkeypatch.delenv(var, raising=False)
    smoke = json.loads((compat_dir / "smoke.json").read_text())
    missed, false_alarms = [], []
    for item in smoke:
        report = check_files([str(compat_dir / "ws" / item["launch_file"])])
        errors = [p for p in report.errors
                  if p.code not in ("missing-node",)]
        if not item["ok"] and not errors:  # roslaunch refuses to load, not to run
            missed.append(item["launch_file"])
        if item["ok"] and any(p.code not in ("unknown-tag",) for p in errors):
            false_alarms.append((item["launch_file"], [str(p) for p in errors]))
    assert missed == []
    assert false_alarms == []


@pytest.mark.timeout(120)
def test_compat_cases_have_no_errors_but_missing_node_packages(compat_dir, monkeypatch):
    """roslaunch loads all 80 cases with their args and env: check must not call any of them
    broken, except for node packages and executables the corpus does not ship."""
    from orchestra.names import load_mappings

    cases = json.loads((compat_dir / "cases.json").read_text())
    false_alarms = []
    for case in cases:
        with monkeypatch.context() as env:
            for name in list(os.environ):
                if name != "PATH":
                    env.delenv(name)
            env.setenv("ROS_PACKAGE_PATH", str(compat_dir / "ws"))
            env.setenv("ROS_DISTRO", "noetic")
            for name, value in case["env"].items():
                env.setenv(name, value)
            args = load_mappings([f"{k}:={v}" for k, v in case["args"].items()])
            report = check_files([str(compat_dir / "ws" / case["launch_file"])], args)
        false_alarms += [str(p) for p in report.errors
                         if p.code not in ("missing-node",)]
    assert false_alarms == []


def test_cli_directory_checks_included_files_through_their_includer(ws):
    write(ws / "launch", "inner.launch", '<launch>\n  <arg name="rate"/>\n'
          '  <param name="p" value="$(arg rate)"/>\n</launch>\n')
    write(ws / "launch", "top.launch", '<launch>\n  <include file="$(dirname)/inner.launch">\n'
          '    <arg name="rate" value="5"/>\n  </include>\n</launch>\n')
    write(ws / "launch", "broken.launch", '<launch>\n  <nod/>\n</launch>\n')
    proc = run_cli(str(ws), env=dict(os.environ))
    assert proc.returncode == 2
    # inner.launch on its own would miss 'rate'; through top.launch it is fine
    assert [line.split(":")[0] for line in proc.stdout.splitlines()] == \
        [str(ws / "launch" / "broken.launch")]
    assert "2 file(s) checked" in proc.stderr


@pytest.mark.timeout(120)
def test_check_flags_every_roslaunch_fixture_roslaunch_rejects(compat_dir, monkeypatch):
    """roslaunch's own test fixtures: each one it rejects gets an error from check. The ones
    it accepts get none, except elements it silently drops (its 'valid' fixtures contain a
    <fake> tag on purpose): check is stricter there by design."""
    fixtures = compat_dir / "fixtures"
    monkeypatch.setenv("ROS_PACKAGE_PATH", str(fixtures / "ws"))
    monkeypatch.setenv("ROS_DISTRO", "noetic")
    missed, false_alarms = [], []
    for expected in sorted((fixtures / "expected").glob("*.json")):
        outcome = json.loads(expected.read_text())
        matches = [p for p in (fixtures / "ws/roslaunch/test/xml").glob(expected.stem + ".*")
                   if p.is_file()]
        if not matches:
            continue  # a fixture directory's helper file, checked through its includer
        report = check_files([str(matches[0])])
        errors = [p for p in report.errors if p.code != "missing-node"]
        if not outcome["ok"] and not errors:
            missed.append(expected.stem)
        if outcome["ok"] and any(p.code != "unknown-tag" for p in errors):
            false_alarms.append([str(p) for p in errors])
    assert missed == []
    assert false_alarms == []


def test_an_include_chain_longer_than_the_stack_is_checked_without_a_traceback(ws):
    from orchestra.launch.interpreter import MAX_INCLUDE_DEPTH
    depth = 1500  # deeper than Python's recursion limit
    for i in range(depth):
        write(ws / "launch", f"f{i}.launch",
              f'<launch>\n  <include file="$(dirname)/f{i + 1}.launch"/>\n</launch>\n')
    write(ws / "launch", f"f{depth}.launch", "<launch/>\n")
    report = check_files([str(ws / "launch" / "f0.launch")])
    assert [p.message for p in report.problems if p.severity == ERROR] == [
        f"<include> attribute 'file': includes nest more than {MAX_INCLUDE_DEPTH} files deep"]


def test_eval_functions_are_not_args_and_refused_grammar_is_reported_statically(ws):
    path = write(ws / "launch", "a.launch",
                 '<launch>\n  <param name="a" value="$(eval radians(90) + pi)"/>\n'
                 '  <group if="false">\n'
                 '    <param name="b" value="$(eval (lambda: 1)())"/>\n  </group>\n</launch>\n')
    report = check_files([path])
    assert codes(report, ERROR) == []
    problem = only(report, "bad-substitution")
    assert problem.location.line == 4 and "lambda expressions are not allowed" in problem.message
