"""``orchestra launch``'s print-and-exit modes read without click agree with the click command.

The entry point reads a command line made only of the output options and launch words
itself (``app/launch_output.py``) and runs it without importing click; these tests pin that
the table is the click command's own options, that every line it reads it reads as click
does, that it hands every other line to click, and that both paths print the same bytes.
"""
from __future__ import annotations

import os
import subprocess
import sys
import textwrap

import click
import pytest

from orchestra.app.cli import launch
from orchestra.app.launch_output import (
    COMPLETION_VARIABLE,
    OUTPUT_OPTIONS,
    parse_output_request,
)
from orchestra.commands import cli


def _click_params(args: list[str]) -> dict:
    with click.Context(cli) as parent:
        ctx = launch.make_context("launch", list(args), parent=parent)
    return ctx.params


def test_output_options_are_the_launch_commands_own_options():
    params = {p.name: p for p in launch.params}
    for option in OUTPUT_OPTIONS:
        param = params[option.dest]
        assert isinstance(param, click.Option)
        assert param.opts == [option.flag] and not param.secondary_opts
        assert param.is_flag == (option.metavar is None), option.flag
        assert param.help == option.help
        if option.metavar:
            assert param.metavar == option.metavar


@pytest.mark.parametrize("args", [
    ["--dump-params", "a.launch"],
    ["a.launch", "--nodes", "x:=1", "y:=a b"],
    ["--args", "/talker", "f.launch"],
    ["--args=/talker", "f.launch"],
    ["--find-node", "talker", "--no-exec", "--dump-plan", "f.launch"],
    ["--ros-args", "f.launch", "rate:=5"],
    ["--files", "pkg", "file.launch", "a:=b"],
    ["--no-exec", "--dump-params", "a.launch", "b.launch"],
    ["--dump-params", "a.launch", "x:=-1"],
])
def test_a_line_read_without_click_is_read_as_click_reads_it(args):
    request = parse_output_request(args)
    assert request is not None
    params = _click_params(args)
    assert request["words"] == params["words"]
    for option in OUTPUT_OPTIONS:
        assert request[option.dest] == params[option.dest], option.flag
    defaults = _click_params(["x.launch"])
    others = {k: v for k, v in params.items()
              if k != "words" and k not in {o.dest for o in OUTPUT_OPTIONS}}
    assert others == {k: defaults[k] for k in others}   # nothing else was given


@pytest.mark.parametrize("args", [
    [],
    ["--dump-params"],                        # no launch file: click's usage error
    ["--dump-params", "x:=1"],
    ["a.launch"],                             # a run
    ["--no-exec", "a.launch"],                # still a run
    ["--dump-params", "-"],                   # stdin
    ["--", "--dump-params", "a.launch"],
    ["--nodes", "--nodes", "a.launch"],       # repeated
    ["--args", "--nodes", "a.launch"],        # a value that looks like an option
    ["--args", "a.launch"],                   # the value took the only file
    ["--args"],
    ["--args=", "a.launch"],
    ["--dump-params=1", "a.launch"],
    ["--dump-params", "--help"],
    ["-h"],
    ["--dump", "a.launch"],                   # not an option (click does not guess)
    ["--dump-params", "-x", "a.launch"],
])
def test_other_lines_are_left_to_click(args):
    assert parse_output_request(args) is None


def test_every_other_option_of_launch_is_left_to_click():
    table = {o.dest for o in OUTPUT_OPTIONS}
    others = [p for p in launch.params if isinstance(p, click.Option) and p.name not in table]
    assert others
    for param in others:
        for flag in param.opts + param.secondary_opts:
            assert parse_output_request(["--dump-params", flag, "a.launch"]) is None, flag
            assert parse_output_request(["--dump-params", "a.launch", flag, "1"]) is None, flag


def test_a_shell_completion_request_is_left_to_click(monkeypatch):
    monkeypatch.setenv(COMPLETION_VARIABLE, "bash_complete")
    assert parse_output_request(["--dump-params", "a.launch"]) is None
    # click's name for the variable is the one checked here
    assert COMPLETION_VARIABLE == "_{}_COMPLETE".format("orchestra".upper())


LAUNCH = textwrap.dedent("""\
    <launch>
      <arg name="rate" default="10" doc="how fast"/>
      <param name="greeting" value="h\u00e9llo"/>
      <param name="ratio" value="0.5"/>
      <group ns="robot">
        <node name="talker" pkg="rospy_tutorials" type="talker.py" args="--rate $(arg rate)">
          <param name="rate" value="$(arg rate)"/>
          <rosparam>{gains: [1, 2.5, x], name: "a: b"}</rosparam>
        </node>
      </group>
    </launch>
    """)

RUN = """\
import sys
import orchestra.app.launch_output
from orchestra.cli import main
if {through_click}:   # main() as it is for every line the table does not cover
    orchestra.app.launch_output.parse_output_request = lambda args: None
try:
    main(sys.argv[1:])
except SystemExit as exc:
    code = exc.code
print("click imported:", "click" in sys.modules, file=sys.stderr)
print("logging imported:", "logging" in sys.modules, file=sys.stderr)
sys.exit(code)
"""


def _run(args: list[str], *, through_click: bool, cwd) -> subprocess.CompletedProcess:
    env = {**os.environ, "ROS_PACKAGE_PATH": str(cwd), "PYTHONIOENCODING": "utf-8"}
    return subprocess.run([sys.executable, "-c", RUN.format(through_click=through_click),
                           "launch", *args], capture_output=True, cwd=cwd, env=env, timeout=60)


@pytest.mark.parametrize("mode", [
    ["--dump-params"], ["--nodes"], ["--files"], ["--args", "/robot/talker"],
    ["--find-node", "/robot/talker"], ["--ros-args"], ["--dump-plan", "--no-exec"],
    ["--find-node", "/nobody"],
])
def test_both_paths_print_the_same_bytes(tmp_path, mode):
    directory = tmp_path / "d\u00efr"      # --files prints it: text click re-encodes
    directory.mkdir()
    (directory / "demo.launch").write_text(LAUNCH, encoding="utf-8")
    args = [*mode, str(directory / "demo.launch"), "rate:=5"]
    fast = _run(args, through_click=False, cwd=tmp_path)
    slow = _run(args, through_click=True, cwd=tmp_path)
    assert b"click imported: True" in slow.stderr
    assert (fast.returncode, fast.stdout, fast.stderr.replace(b"False", b"True")) == \
        (slow.returncode, slow.stdout, slow.stderr)
    if mode == ["--find-node", "/nobody"]:   # the error line (printed by click) and code
        assert fast.returncode == 2
        assert b"orchestra: error: cannot find node named [/nobody]" in fast.stderr
    else:
        assert fast.returncode == 0 and fast.stdout.strip()
        # text outside ASCII is printed by click.echo, as on the click path
        assert (b"click imported: False" in fast.stderr) == fast.stdout.isascii()


def test_a_warning_is_logged_alike_and_logging_is_imported_only_for_it(tmp_path):
    """The fast path sets logging up when something is first logged (importing ``logging`` is
    a tenth of such a process's own work): the warning line is the click path's, and a file
    that logs nothing imports no logging."""
    (tmp_path / "quiet.launch").write_text(LAUNCH, encoding="utf-8")
    (tmp_path / "warns.launch").write_text(LAUNCH.replace("<launch>", "<launch><master/>"),
                                           encoding="utf-8")
    quiet = _run(["--nodes", str(tmp_path / "quiet.launch")], through_click=False, cwd=tmp_path)
    assert quiet.returncode == 0 and b"logging imported: False" in quiet.stderr
    args = ["--nodes", str(tmp_path / "warns.launch")]
    fast = _run(args, through_click=False, cwd=tmp_path)
    slow = _run(args, through_click=True, cwd=tmp_path)
    warning = f"[WARNING] orchestra.launch.interpreter: {tmp_path / 'warns.launch'}:1: " \
              "ignoring defunct <master> tag\n"
    assert fast.stderr.decode().startswith(warning)
    assert (fast.returncode, fast.stdout, fast.stderr.replace(b"False", b"True")) == \
        (slow.returncode, slow.stdout, slow.stderr)
