"""``orchestra logs [NODE] [-f]``: roslaunch-logs, and a tail of one node's log files.

Which run: the orchestra launch at ROS_MASTER_URI (its snapshot names its log directory),
else the run whose ``/run_id`` that master holds, else the ``latest`` run. A node's files are
found by roslaunch's naming (``robot1-listener-3-stdout.log``, ``-stderr.log``, and the
node's own ``robot1-listener-3.log``), so nodes of finished runs and of real roslaunch runs
are found too.
"""
from __future__ import annotations

import os
import re
import time
from collections.abc import Iterator
from typing import Any

import click

from orchestra.completion import complete_node_names
from orchestra.errors import OrchestraError

_FILE = re.compile(r"^(?P<base>.+)-(?P<counter>\d+)(?:-stdout|-stderr)?\.log$")


def run_log_dir(master_uri: str) -> str:
    """The log directory of the run at ``master_uri`` (see the module docstring)."""
    from orchestra.rpc import TRANSPORT_ERRORS, call
    from orchestra.supervise.output import log_dir_root
    from orchestra.supervise.status import launches_at

    for launch in launches_at(master_uri):
        if launch.get("log_dir"):
            return str(launch["log_dir"])
    root = log_dir_root()
    try:
        answer: Any = call(master_uri, "getParam", "/orchestra_logs", "/run_id", timeout=2.0)
        code, _, run_id = answer
        if code == 1 and isinstance(run_id, str) and os.path.isdir(os.path.join(root, run_id)):
            return os.path.join(root, run_id)
    except TRANSPORT_ERRORS:
        pass
    latest = os.path.join(root, "latest")
    if os.path.isdir(latest):
        return os.path.realpath(latest)
    raise OrchestraError(f"no run log directory: nothing runs at {master_uri} and {root} "
                         "has no latest run")


def node_files(log_dir: str) -> dict[str, list[str]]:
    """Node full name -> its log files in ``log_dir`` (sorted), by roslaunch's file names."""
    found: dict[str, list[str]] = {}
    try:
        names = sorted(os.listdir(log_dir))
    except OSError:
        return found
    for name in names:
        match = _FILE.match(name)
        if match:
            node = "/" + match["base"].replace("-", "/")
            found.setdefault(node, []).append(os.path.join(log_dir, name))
    return found


def _lines_of(path: str, count: int) -> list[str]:
    try:
        with open(path, "rb") as fh:
            fh.seek(0, os.SEEK_END)
            fh.seek(max(0, fh.tell() - 256 * 1024))
            data = fh.read()
    except OSError:
        return []
    return data.decode("utf-8", "replace").splitlines()[-count:] if count else []


def _follow(paths: list[str], interval: float = 0.2) -> Iterator[tuple[str, str]]:
    """(path, new text) as the files grow, like ``tail -f`` (polls: files have no events)."""
    offsets = {p: os.path.getsize(p) if os.path.exists(p) else 0 for p in paths}
    while True:
        for path in paths:
            try:
                size = os.path.getsize(path)
            except OSError:
                continue
            if size < offsets[path]:          # rotated: start over
                offsets[path] = 0
            if size > offsets[path]:
                with open(path, "rb") as fh:
                    fh.seek(offsets[path])
                    data = fh.read()
                offsets[path] += len(data)
                yield path, data.decode("utf-8", "replace")
        time.sleep(interval)


@click.command()
@click.argument("node", required=False, shell_complete=complete_node_names)
@click.option("-f", "--follow", is_flag=True, help="Keep printing what the files get (tail -f).")
@click.option("-n", "--lines", "count", type=click.IntRange(min=0), default=20,
              show_default=True, help="Last lines of each file to print first.")
def logs(node: str | None, follow: bool, count: int) -> None:
    """Without NODE: the log directory of the run at ROS_MASTER_URI (roslaunch-logs).
    With NODE: the last lines of its log files, and with -f what they get next."""
    from orchestra.master import master_uri_from_env
    from orchestra.suggest import did_you_mean
    from orchestra.supervise.status import launches_at

    uri = master_uri_from_env()
    log_dir = run_log_dir(uri)
    if node is None:
        click.echo(log_dir)
        return
    name = node if node.startswith("/") else "/" + node
    files = node_files(log_dir)
    paths = files.get(name)
    if not paths:
        running = {n["name"] for launch in launches_at(uri) for n in launch["nodes"]}
        if name in running:
            raise OrchestraError(f"node {name} has no log files in {log_dir}: its output goes "
                                 "to the screen (output=\"screen\")")
        raise OrchestraError(f"no node {name} in this launch's logs ({log_dir})"
                             f"{did_you_mean(name, set(files) | running)}")
    for i, path in enumerate(paths):
        if len(paths) > 1:
            click.echo(f"{chr(10) if i else ''}==> {path} <==")
        for line in _lines_of(path, count):
            click.echo(line)
    if follow:
        try:
            for path, text in _follow(paths):
                prefix = f"[{os.path.basename(path)}] " if len(paths) > 1 else ""
                for line in text.splitlines():
                    click.echo(prefix + line)
        except KeyboardInterrupt:
            pass
