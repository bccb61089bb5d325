"""``orchestra launch [PKG] FILE [name:=value ...]``: resolve a launch file, dump it or run it.

Start-up time matters (tools call ``--dump-plan`` hundreds of times), so this module imports
only click and the supervision options at import time; the interpreter, YAML and JSON are
imported when the command runs.
"""
from __future__ import annotations

import os
import sys
from typing import Any

import click

from orchestra.errors import OrchestraError
from orchestra.supervise.cli import run_options

_OWN_OPTIONS = ("words", "dump_plan", "dump_params", "nodes", "node_args", "files",
                "find_node", "ros_args", "no_exec")


def _find_in_package(package: str, filename: str) -> str:
    """FILE anywhere below PKG's directory (roslaunch's ``roslaunch PKG FILE`` rule)."""
    from orchestra.packages import find_package
    root = find_package(package)
    direct = os.path.join(root, filename)
    if os.path.isfile(direct):
        return direct
    base = os.path.basename(filename)
    matches = []
    for dirpath, dirnames, files in os.walk(root, followlinks=True):
        dirnames[:] = sorted(d for d in dirnames if not d.startswith("."))
        if base in files:
            matches.append(os.path.join(dirpath, base))
    if not matches:
        raise OrchestraError(f"[{filename}] is neither a launch file in package [{package}] "
                             "nor a launch file name")
    if len(matches) > 1:
        listing = "".join(f"\n  {m}" for m in matches)
        raise OrchestraError(f"multiple files named [{filename}] in package [{package}]:"
                             f"{listing}\nname one by its path")
    return matches[0]


def split_words(words: tuple[str, ...]) -> tuple[list[str], dict[str, str]]:
    """Launch file paths and ``name:=value`` args from the command line words."""
    from orchestra.names import load_mappings
    positional = [w for w in words if ":=" not in w]
    args = load_mappings([w for w in words if ":=" in w])
    if not positional:
        raise click.UsageError("give a launch file: orchestra launch [PKG] FILE [name:=value ...]")
    first = positional[0]
    if first == "-" or os.path.isfile(first) or len(positional) != 2 \
            or first.endswith((".launch", ".xml", ".yaml", ".yml")):
        files = positional
    else:
        files = [_find_in_package(first, positional[1])]
    return files, args


def _interpret(files: list[str], args: dict[str, str], *, no_exec: bool, roscore: bool):
    from orchestra.launch.interpreter import Interpreter, LoadOptions
    interp = Interpreter(LoadOptions(args=args, no_exec=no_exec, roscore=roscore))
    for path in files:
        if path == "-":
            from orchestra.launch.xml import parse_string
            interp.load_entity(parse_string(sys.stdin.read(), "<stdin>"), "<stdin>")
        else:
            missing = not os.path.isfile(path)
            if missing:
                raise OrchestraError(f"launch file not found: {path}")
            interp.load_file(os.path.abspath(path))
    return interp


def _dump_json(plan: Any) -> str:
    import json

    from orchestra.launch.interpreter import binary_to_json
    doc = plan.to_json()
    from orchestra.supervise.command import exec_table
    doc["exec"] = exec_table(plan)
    return json.dumps(doc, indent=1, default=binary_to_json)


def _find_node(plan: Any, name: str) -> Any:
    from orchestra.names import canonicalize, make_global_ns
    wanted = canonicalize(name if name.startswith("/") else make_global_ns(
        os.environ.get("ROS_NAMESPACE", "/")) + name)
    found = [n for n in (*plan.nodes, *plan.tests) if n.name and n.full_name == wanted]
    if not found:
        names = "".join(f"\n * {n.full_name}" for n in (*plan.nodes, *plan.tests) if n.name)
        raise OrchestraError(f"cannot find node named [{wanted}]. Node names are:{names}")
    if len(found) > 1:
        raise OrchestraError(f"multiple nodes named [{wanted}]")
    return found[0]


def _node_args(plan: Any, name: str) -> str:
    import shlex
    node = _find_node(plan, name)
    from orchestra.supervise.command import exec_table
    entry = exec_table(plan, include_tests=True).get(node.full_name)
    if entry is None:
        raise OrchestraError(f"no command line for node [{node.full_name}]")
    env = [f"{k}={shlex.quote(v)}" for k, v in entry["env"].items()]
    return " ".join([*env, *(shlex.quote(a) for a in entry["argv"])])


def _ros_args(paths: list[str], args: dict[str, str]) -> str:
    from orchestra.launch.interpreter import declared_args, parse_launch_file
    declared = []
    for path in paths:
        if path == "-":
            from orchestra.launch.xml import parse_string
            declared += declared_args(parse_string(sys.stdin.read(), "<stdin>"), "<stdin>", args)
        else:
            declared += declared_args(parse_launch_file(path), path, args)
    required = [a for a in declared if not a.default]
    optional = [a for a in declared if a.default]
    if not required and not optional:
        return "No arguments."
    lines = []
    if required:
        lines.append("Required Arguments:")
        lines += [f"  {a.name}: {a.doc or 'undocumented'}" for a in sorted(required,
                                                                            key=lambda a: a.name)]
    if optional:
        lines.append("Optional Arguments:")
        lines += [f"  {a.name} (default \"{a.default}\"): {a.doc or 'undocumented'}"
                  for a in sorted(optional, key=lambda a: a.name)]
    return "\n".join(lines)


@click.command(context_settings={"help_option_names": ["-h", "--help"]})
@click.argument("words", nargs=-1)
@click.option("--dump-plan", is_flag=True, help="Print the resolved plan as JSON and exit.")
@click.option("--dump-params", is_flag=True, help="Print the parameters as YAML and exit.")
@click.option("--nodes", is_flag=True, help="List the nodes' full names and exit.")
@click.option("--args", "node_args", metavar="NODE", help="Print NODE's command line and exit.")
@click.option("--files", is_flag=True, help="List the launch files read and exit.")
@click.option("--find-node", metavar="NODE", help="Print the file declaring NODE and exit.")
@click.option("--ros-args", is_flag=True, help="Show the launch file's <arg>s and exit.")
@click.option("--no-exec", is_flag=True,
              help="Do not run command= params; record them as {__command__: cmd}.")
@run_options
def launch(words: tuple[str, ...], dump_plan: bool, dump_params: bool, nodes: bool,
           node_args: str | None, files: bool, find_node: str | None, ros_args: bool,
           no_exec: bool, **run_opts: Any) -> None:
    """Resolve and run a roslaunch file: orchestra launch [PKG] FILE [name:=value ...]."""
    paths, args = split_words(words)
    if ros_args:
        click.echo(_ros_args(paths, args))
        return
    dumping = dump_plan or dump_params or nodes or bool(node_args) or files or bool(find_node)
    # like roslaunch, everything but the two dumps loads roscore.xml's params first; when the
    # plan is going to run, command= params always run (--no-exec only shapes the dumps)
    interp = _interpret(paths, args, no_exec=no_exec and dumping,
                        roscore=not (dump_plan or dump_params))
    plan = interp.plan()
    if dump_plan:
        click.echo(_dump_json(plan))
    elif dump_params:
        import yaml

        from orchestra.launch.interpreter import Binary
        yaml.SafeDumper.add_representer(Binary, yaml.SafeDumper.represent_binary)
        # roslaunch prints the YAML document (which ends in a newline) with print(), so its
        # output ends in an empty line; scripts diff the two, so match it byte for byte
        click.echo(yaml.safe_dump(dict(plan.params), default_flow_style=False))
    elif nodes:
        names = [n.full_name for n in (*plan.nodes, *plan.tests) if n.name]
        if names:
            click.echo("\n".join(names))
    elif node_args:
        click.echo(_node_args(plan, node_args))
    elif files:
        seen: list[str] = []
        for path in plan.files_loaded:
            full = os.path.abspath(path)
            if full not in seen:
                seen.append(full)
        click.echo("\n".join(seen))
    elif find_node:
        node = _find_node(plan, find_node)
        click.echo(node.filename or "")
    else:
        from orchestra.supervise.cli import run_plan
        options = dict(run_opts)
        options["no_exec"] = False
        sys.exit(run_plan(plan, options))


__all__ = ["launch", "split_words"]
