"""``orchestra check``: every problem in launch files, starting nothing.

The checking is launch/check.py's; this command is composed here, in the app layer, because
``--check-machines`` adds remote/'s preflight of every remote machine, and remote/ sits above
launch/.
"""
from __future__ import annotations

import os

import click

from orchestra.launch import convert as conversion


def _expand(paths: list[str]) -> list[str]:
    """Files as given; a directory stands for every launch file (XML or YAML) under it."""
    files: list[str] = []
    for path in paths:
        if not os.path.isdir(path):
            files.append(path)
            continue
        for root, dirs, names in os.walk(path):
            dirs.sort()
            for name in sorted(names):
                candidate = os.path.join(root, name)
                if conversion.is_launch_file(candidate, "xml") or \
                        conversion.is_launch_file(candidate, "yaml"):
                    files.append(candidate)
    return files


def _add_machine_warnings(report) -> None:
    """``--check-machines``: the launch's own preflight per remote machine, as warnings
    (imported only when asked: it is the one part of ``check`` beyond launch files)."""
    from orchestra.errors import Location
    from orchestra.launch.check import WARNING, Problem
    from orchestra.remote.reach import check_machines

    for problem in check_machines(report.plans):
        where = problem.location or Location(report.files[0] if report.files else "<launch>")
        report.add(Problem(WARNING, where, problem.message, "machine"))


@click.command()
@click.argument("words", nargs=-1, required=True, metavar="FILE|DIR... [name:=value ...]")
@click.option("--strict", is_flag=True, help="Warnings fail the check too.")
@click.option("--json", "as_json", is_flag=True,
              help="Print the problems as one JSON document (for editors and CI).")
@click.option("--check-machines", is_flag=True,
              help="Also connect to every remote <machine> (ssh, env-loader, orchestra and "
                   "the nodes' executables there) and warn about those that fail.")
@click.pass_context
def check(ctx: click.Context, words: tuple[str, ...], strict: bool, as_json: bool,
          check_machines: bool) -> None:
    """Report every problem in launch files (and what they include), starting nothing.

    A DIR stands for every launch file under it. Args apply to every file checked.

    Each line is FILE:LINE:COLUMN: error|warning: message [code]. Exit status: 0 when no
    errors were found (warnings allowed unless --strict), 2 otherwise (as every command
    exits on a user's mistake).
    """
    from orchestra.launch.check import check_files, check_tree
    from orchestra.names import load_mappings

    paths = [w for w in words if ":=" not in w]
    args = load_mappings([w for w in words if ":=" in w])
    if not paths:
        raise click.UsageError("give at least one launch file or directory")
    if any(os.path.isdir(path) for path in paths):
        report = check_tree(_expand(paths), args)
    else:
        report = check_files(paths, args)
    if check_machines:
        _add_machine_warnings(report)
    if as_json:
        import json

        click.echo(json.dumps({"files": report.files,
                               "problems": [p.to_json() for p in report.sorted()]}, indent=1))
    else:
        for problem in report.sorted():
            click.echo(str(problem))
    errors, warnings = len(report.errors), len(report.warnings)
    summary = (f"{len(report.files)} file(s) checked: {errors} error(s), "
               f"{warnings} warning(s)")
    click.echo(summary, err=True)
    if errors or (strict and warnings):
        ctx.exit(2)
