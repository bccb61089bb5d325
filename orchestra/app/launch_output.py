"""The print-and-exit modes of ``orchestra launch``: --dump-plan, --dump-params, --nodes,
--args, --files, --find-node, --ros-args (and --no-exec, which shapes the dumps).

Tools call these hundreds of times (compare scripts, IDEs, completion), so their start-up is
part of the product, and click's import alone is a fifth of a one-node ``--dump-params``.
``OUTPUT_OPTIONS`` is the one definition of these options: the click command is built from
it (``orchestra/app/cli.py``), and ``parse_output_request`` reads a command line made of
nothing else without importing click (``orchestra/cli.py``). Any other token, or anything
click would read differently, makes it answer None and click parses the line as always;
tests/test_launch_output.py checks that both readings agree. Both paths then print through
``write_outputs`` here. This module imports nothing of click, the interpreter or YAML at
import time.
"""
from __future__ import annotations

import os
import sys
from typing import Any, NamedTuple


class OutputOption(NamedTuple):
    """One option of ``orchestra launch``'s print-and-exit modes. (A NamedTuple: it is built
    on this start-up path, where a frozen dataclass costs ~0.4 ms to create.)"""

    flag: str
    #: the click parameter name (the keyword of the command's callback)
    dest: str
    help: str
    #: a value option (``--args NODE``) when set, else a flag
    metavar: str | None = None


OUTPUT_OPTIONS = (
    OutputOption("--dump-plan", "dump_plan", "Print the resolved plan as JSON and exit."),
    OutputOption("--dump-params", "dump_params", "Print the parameters as YAML and exit."),
    OutputOption("--nodes", "nodes", "List the nodes' full names and exit."),
    OutputOption("--args", "node_args", "Print NODE's command line and exit.", "NODE"),
    OutputOption("--files", "files", "List the launch files read and exit."),
    OutputOption("--find-node", "find_node", "Print the file declaring NODE and exit.", "NODE"),
    OutputOption("--ros-args", "ros_args", "Show the launch file's <arg>s and exit."),
    OutputOption("--no-exec", "no_exec",
                 "Do not run command= params; record them as {__command__: cmd}."),
)

#: click's shell completion runs when this is set (click's name for it: ``_<PROG>_COMPLETE``)
COMPLETION_VARIABLE = "_ORCHESTRA_COMPLETE"


def parse_output_request(args: list[str]) -> dict[str, Any] | None:
    """The keyword arguments click would pass ``launch`` for ``args`` (what follows
    ``orchestra launch``), when they are only the options above and launch words and name
    an output mode; None for anything else (click then reads the line: help, run options,
    ``--``, ``-`` for stdin, a repeated option, a value that looks like an option...)."""
    if os.environ.get(COMPLETION_VARIABLE):
        return None
    by_flag = {option.flag: option for option in OUTPUT_OPTIONS}
    values: dict[str, Any] = {o.dest: None if o.metavar else False for o in OUTPUT_OPTIONS}
    seen: set[str] = set()
    words: list[str] = []
    tokens = iter(args)
    for token in tokens:
        if not token.startswith("-"):
            words.append(token)
            continue
        flag, equals, value = token.partition("=")
        option = by_flag.get(flag)
        if option is None or option.dest in seen or (equals and option.metavar is None):
            return None
        seen.add(option.dest)
        if option.metavar is None:
            values[option.dest] = True
            continue
        if not equals:
            value = next(tokens, "")
        if not value or value.startswith("-"):
            return None
        values[option.dest] = value
    if not any(":=" not in word for word in words) or not prints_and_exits(values):
        return None
    values["words"] = tuple(words)
    return values


def prints_and_exits(modes: dict[str, Any]) -> bool:
    """Whether ``modes`` (the options above) ask for output instead of a run."""
    return any(modes[o.dest] for o in OUTPUT_OPTIONS if o.dest != "no_exec")


def echo(text: str) -> None:
    """``click.echo(text)`` without importing click for plain text: ASCII without an escape
    character is written as it is by click too (click strips ANSI codes off a terminal and
    re-encodes for odd stdout encodings; such text goes to click)."""
    if sys.stdout is not None and text.isascii() and "\x1b" not in text:
        sys.stdout.write(text + "\n")
        sys.stdout.flush()
        return
    import click

    click.echo(text)


def write_outputs(paths: list[str], args: dict[str, str], modes: dict[str, Any]) -> bool:
    """Print what ``modes`` asks for about the launch of ``paths`` with ``args``; False (and
    nothing printed) when it asks for none, i.e. for a run."""
    from orchestra.launch.load import interpret, ros_args_text

    if modes["ros_args"]:
        echo(ros_args_text(paths, args))
        return True
    if not prints_and_exits(modes):
        return False
    # like roslaunch, everything but the two dumps loads roscore.xml's params first
    dump_plan, dump_params = modes["dump_plan"], modes["dump_params"]
    plan = interpret(paths, args, no_exec=modes["no_exec"],
                     roscore=not (dump_plan or dump_params)).plan()
    if dump_plan:
        echo(_dump_json(plan))
    elif dump_params:
        from orchestra.params.dump_launch import dump_launch_params

        # roslaunch prints the YAML document (which ends in a newline) with print(), so its
        # output ends in an empty line; scripts diff the two, so match it byte for byte
        echo(dump_launch_params(dict(plan.params)))
    elif modes["nodes"]:
        names = [n.full_name for n in (*plan.nodes, *plan.tests) if n.name]
        if names:
            echo("\n".join(names))
    elif modes["node_args"]:
        echo(_node_args(plan, modes["node_args"]))
    elif modes["files"]:
        seen: list[str] = []
        for path in plan.files_loaded:
            full = os.path.abspath(path)
            if full not in seen:
                seen.append(full)
        echo("\n".join(seen))
    else:
        from orchestra.launch.load import find_node

        echo(find_node(plan, modes["find_node"]).filename or "")
    return True


def run_output_request(request: dict[str, Any]) -> None:
    """``orchestra launch`` for a ``parse_output_request`` answer, without click."""
    from orchestra.launch.load import split_words

    # no stop_signals.record() as a run has: this starts nothing, so a Ctrl-C (even during a
    # slow command= param) simply ends it (KeyboardInterrupt: exit 130, the child killed)
    paths, args = split_words(request["words"])
    write_outputs(paths, args, request)


def _dump_json(plan: Any) -> str:
    import json

    from orchestra.launch.interpreter import binary_to_json
    from orchestra.supervise.command import exec_table

    doc = plan.to_json()
    doc["exec"] = exec_table(plan)
    return json.dumps(doc, indent=1, default=binary_to_json)


def _node_args(plan: Any, name: str) -> str:
    import shlex

    from orchestra.errors import OrchestraError
    from orchestra.launch.load import find_node
    from orchestra.supervise.command import exec_table

    node = find_node(plan, name)
    entry = exec_table(plan, include_tests=True).get(node.full_name)
    if entry is None:
        raise OrchestraError(f"no command line for node [{node.full_name}]")
    env = [f"{k}={shlex.quote(v)}" for k, v in entry["env"].items()]
    return " ".join([*env, *(shlex.quote(a) for a in entry["argv"])])
