#!/usr/bin/env python3
"""What ``orchestra launch --nodes|--dump-params|--files|--args NODE`` prints, for demos.

    orchestra_resolve.py "PKG FILE" ["PKG FILE" ...]

The counterpart of roslaunch_resolve.py: runs orchestra's own command line (``main``) once
per option in one process, so comparing every bundled demo costs one interpreter start-up,
not forty. Prints {"PKG FILE": {"nodes": text, "params": text, "files": text,
"args": {node: text}}}; a failing option is recorded as {"error": text}.
"""
import contextlib
import io
import json
import sys

from orchestra.cli import main


def captured(*argv):
    out, err = io.StringIO(), io.StringIO()
    code = 0
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            main(["launch", *argv])
        except SystemExit as exc:
            code = exc.code
    return out.getvalue() if code == 0 else {"error": f"exit {code}: {err.getvalue()}"}


report = {}
for words in sys.argv[1:]:
    nodes = captured("--nodes", *words.split())
    report[words] = {
        "nodes": nodes,
        "params": captured("--dump-params", *words.split()),
        "files": captured("--files", *words.split()),
        "args": {node: captured("--args", node, *words.split())
                 for node in (nodes.split() if isinstance(nodes, str) else [])},
    }
print(json.dumps(report))
