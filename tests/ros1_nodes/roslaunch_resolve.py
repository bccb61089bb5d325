#!/usr/bin/python3
"""What real roslaunch's --nodes, --dump-params, --files and --args print, for launch files.

    roslaunch_resolve.py "PKG FILE" ["PKG FILE" ...]   (or a path instead of "PKG FILE")

Runs the very functions roslaunch's command line calls for those options, in one process
(a roslaunch start-up per option and file would cost the test suite seconds), and prints one
JSON object: {"PKG FILE": {"nodes": text, "params": text, "files": text,
"args": {node: text}}}. A failing option is recorded as {"error": text}.
"""
import contextlib
import io
import json
import sys

from roslaunch import node_args, param_dump, rlutil


def captured(fn, *args):
    out = io.StringIO()
    try:
        with contextlib.redirect_stdout(out):
            fn(*args)
    except SystemExit as exc:
        return {"error": f"exit {exc.code}: {out.getvalue()}"}
    return out.getvalue()


report = {}
for words in sys.argv[1:]:
    files = rlutil.resolve_launch_arguments(words.split())
    nodes = captured(node_args.print_node_list, files)
    report[words] = {
        "nodes": nodes,
        "params": captured(param_dump.dump_params, files),
        "files": captured(rlutil.print_file_list, files),
        "args": {node: captured(node_args.print_node_args, node, files)
                 for node in nodes.split()},
    }
print(json.dumps(report))
