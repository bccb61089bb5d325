"""The interpreter and `orchestra check` apply the same tag rules: the ones of launch/rules.py.

Each test walks the whole rule table and compares, element by element, what the interpreter
does with what check reports, so a rule changed in one place and not the other fails here.
"""
from __future__ import annotations

import pytest

from orchestra.errors import OrchestraError
from orchestra.launch import rules
from orchestra.launch.check import Finding, check_files
from orchestra.launch.entity import Entity
from orchestra.launch.interpreter import Interpreter, LoadOptions
from orchestra.launch.rules import LaunchError

# A valid element of every tag: its required attributes with values that work (test data)
BASE: dict[str, dict[str, str]] = {
    "node": {"pkg": "mypkg", "type": "t", "name": "n"},
    "test": {"pkg": "mypkg", "type": "t", "test-name": "tn"},
    "machine": {"name": "m", "address": "localhost"},
    "param": {"name": "p", "value": "1"},
    "rosparam": {"param": "r"},
    "arg": {"name": "a", "default": "1"},
    "include": {"file": "$(dirname)/inner.launch"},
    "group": {"ns": "g"},
    "remap": {"from": "a", "to": "b"},
    "env": {"name": "E", "value": "v"},
    "master": {},
}
LEAF_TEXT = {"rosparam": "1"}
TAGS = sorted(BASE)
# values tried on every attribute of a kind other than plain text
VALUES = ["true", "false", "True", "FALSE", "1", "0", "yes", "", "-1", "2.5", "x", "log",
          "screen", "node", "ROS_HOME", "ros_home", "load", "dump", "never", "yaml", "Int"]
TYPED = [(tag, name) for tag in TAGS for name, attr in rules.TAGS[tag].attributes.items()
         if attr.kind is not rules.STRING]


class _Recording(Interpreter):
    """The interpreter, keeping its warnings as values and going on after an error."""

    def __init__(self) -> None:
        super().__init__(LoadOptions(no_exec=True))
        self.findings: list[Finding] = []
        self.errors: list[OrchestraError] = []

    def _children(self, children, scope, default_machine):
        for entity in children:
            try:
                default_machine = super()._children([entity], scope, default_machine)
            except OrchestraError as exc:
                self.errors.append(exc)
        return default_machine

    def _warn(self, entity: Entity, message: str, code: str = rules.INVALID,
              attribute: str | None = None) -> None:
        self.findings.append(Finding(entity.location, message, code, entity.tag,
                                           attribute))


def _xml_attrs(attrs: dict[str, str]) -> str:
    return "".join(f' {k}="{v}"' for k, v in attrs.items())


def _element(tag: str, attrs: dict[str, str], inner: str = "") -> str:
    body = inner or LEAF_TEXT.get(tag, "")
    return f"<{tag}{_xml_attrs(attrs)}>{body}</{tag}>" if body else f"<{tag}{_xml_attrs(attrs)}/>"


@pytest.fixture
def launch_dir(tmp_path, monkeypatch):
    pkg = tmp_path / "ws" / "mypkg"
    pkg.mkdir(parents=True)
    (pkg / "package.xml").write_text("<package format='2'><name>mypkg</name>"
                                     "<version>1.0.0</version></package>")
    exe = pkg / "t"
    exe.write_text("#!/bin/sh\n")
    exe.chmod(0o755)
    monkeypatch.setenv("ROS_PACKAGE_PATH", str(tmp_path / "ws"))
    for var in ("ROS_NAMESPACE",):
        monkeypatch.delenv(var, raising=False)
    (tmp_path / "inner.launch").write_text("<launch/>\n")
    return tmp_path


def _run_both(directory, element: str):
    """(interpreter findings, interpreter errors, check problems) for one element on line 2."""
    path = directory / "a.launch"
    path.write_text(f"<launch>\n  {element}\n</launch>\n")
    interp = _Recording()
    try:
        interp.load_file(str(path))
    except OrchestraError as exc:
        interp.errors.append(exc)
    report = check_files([str(path)])
    return interp.findings, interp.errors, report.problems


def _interpreter_codes(findings, errors, attribute=None):
    found = {(f.code, f.attribute) for f in findings}
    found |= {(e.code, e.attribute) for e in errors if isinstance(e, LaunchError)}
    return {code for code, attr in found if attribute is None or attr == attribute}


@pytest.mark.parametrize("tag", TAGS)
def test_a_valid_element_of_every_tag_passes_both(launch_dir, tag):
    findings, errors, problems = _run_both(launch_dir, _element(tag, BASE[tag]))
    assert errors == []
    assert [f for f in findings if f.code != "defunct-tag"] == []
    assert [p for p in problems if p.code not in ("unused-arg", "launch", "defunct-tag")] == []


@pytest.mark.parametrize("tag,attribute", [(t, a) for t in TAGS for a in rules.TAGS[t].required])
def test_every_required_attribute_is_required_by_both(launch_dir, tag, attribute):
    attrs = {k: v for k, v in BASE[tag].items() if k != attribute}
    findings, errors, problems = _run_both(launch_dir, _element(tag, attrs))
    [error] = errors
    assert isinstance(error, LaunchError)
    assert (error.code, error.tag, error.attribute) == (rules.MISSING_ATTRIBUTE, tag, attribute)
    [problem] = [p for p in problems if p.code == rules.MISSING_ATTRIBUTE]
    assert f"'{attribute}'" in problem.message and problem.location.line == 2


def test_required_attributes_are_what_the_table_says_and_nothing_else(launch_dir):
    """Removing an attribute the table does not require is never a missing-attribute."""
    for tag in TAGS:
        for name in BASE[tag]:
            if name in rules.TAGS[tag].required:
                continue
            attrs = {k: v for k, v in BASE[tag].items() if k != name}
            findings, errors, problems = _run_both(launch_dir, _element(tag, attrs))
            assert rules.MISSING_ATTRIBUTE not in _interpreter_codes(findings, errors)
            assert rules.MISSING_ATTRIBUTE not in {p.code for p in problems}


@pytest.mark.parametrize("tag", TAGS)
def test_known_and_unknown_attributes_agree(launch_dir, tag):
    for name in [*rules.TAGS[tag].attributes, "bogus", "Name", "respwan"]:
        if name in ("if", "unless") or name in BASE[tag]:
            continue
        attrs = {**BASE[tag], name: "x"}
        findings, errors, problems = _run_both(launch_dir, _element(tag, attrs))
        interpreter = rules.UNKNOWN_ATTRIBUTE in _interpreter_codes(findings, errors, name)
        checker = any(p.code == rules.UNKNOWN_ATTRIBUTE and f"'{name}'" in p.message
                      for p in problems)
        assert interpreter == checker == (name not in rules.TAGS[tag].allowed), (tag, name)


@pytest.mark.parametrize("tag,name", TYPED)
def test_typed_attribute_values_are_accepted_and_refused_alike(launch_dir, tag, name):
    """bool (true/false only), if/unless (also 1/0), numbers and choices: every value the
    interpreter refuses check refuses, and the other way round."""
    disagreements = []
    for value in VALUES:
        attrs = {**BASE[tag], name: value}
        findings, errors, problems = _run_both(launch_dir, _element(tag, attrs))
        interpreter = rules.BAD_VALUE in _interpreter_codes(findings, errors, name)
        checker = any(p.code == rules.BAD_VALUE for p in problems)
        if interpreter != checker:
            disagreements.append((value, interpreter, checker))
    assert disagreements == []


def test_pass_all_args_takes_only_true_or_false_in_both(launch_dir):
    findings, errors, problems = _run_both(
        launch_dir, _element("include", {**BASE["include"], "pass_all_args": "1"}))
    assert [e.code for e in errors if isinstance(e, LaunchError)] == [rules.BAD_VALUE]
    assert [p.code for p in problems if p.severity == "error"] == [rules.BAD_VALUE]


@pytest.mark.parametrize("parent", ["launch", *TAGS])
def test_children_rules_agree(launch_dir, parent):
    for child in [*TAGS, "nod", "Param"]:
        inner = _element(child, BASE.get(child.lower(), {}))
        if parent == "launch":
            element = inner
        else:
            element = _element(parent, BASE[parent], inner)
        findings, errors, problems = _run_both(launch_dir, element)
        child_line = [f for f in findings if f.code == rules.UNKNOWN_TAG]
        interpreter = bool(child_line) or any(
            isinstance(e, LaunchError) and e.tag == child for e in errors)
        checker = any(p.code == rules.UNKNOWN_TAG for p in problems)
        rule = rules.TAGS[parent]
        assert interpreter == checker == (rule.child_tag(child) is None), (parent, child)
