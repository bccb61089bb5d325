"""Run-time side of ``orchestra launch`` and the ``orchestra status`` command.

``run_options`` is applied by ``orchestra.launch.cli.launch`` to add the run-time flags;
``run_plan(plan, options)`` runs a plan and returns the process exit code. Importing this
module must stay cheap (``--dump-plan`` imports it on every call): only click here, the
supervisor is imported inside the functions.
"""
from __future__ import annotations

import json
from collections.abc import Callable
from typing import Any

import click

_OPTIONS = [
    click.option("--screen", "force_screen", is_flag=True,
                 help="Force every node's output to the console."),
    click.option("--log", "force_log", is_flag=True,
                 help="Force every node's output to log files."),
    click.option("--wait", is_flag=True,
                 help="Wait for the master at ROS_MASTER_URI instead of starting one."),
    click.option("--required", "all_required", is_flag=True,
                 help="Treat every node as required: any death stops the launch."),
    click.option("--local", is_flag=True,
                 help="Do not launch remote nodes (those of a <machine> that is not this one)."),
    click.option("--disable-title", is_flag=True, help="Do not set the terminal title."),
    click.option("-p", "--port", type=click.IntRange(0, 65535), default=None,
                 help="Port of the master to use or start (default: from ROS_MASTER_URI)."),
    click.option("--run-id", "--run_id", "run_id", default=None,
                 help="The run id (default: the master's /run_id, else a new uuid1)."),
    click.option("--sigint-timeout", type=click.FloatRange(min=0), default=15.0,
                 show_default=True, help="Seconds a node has to exit after SIGINT."),
    click.option("--sigterm-timeout", type=click.FloatRange(min=0), default=2.0,
                 show_default=True, help="Seconds a node has to exit after SIGTERM, then SIGKILL."),
    click.option("--node-timeout", "node_timeouts", multiple=True,
                 metavar="NODE=SIGINT[,SIGTERM]",
                 help="Per-node stop timeouts, e.g. /camera=30,5 (repeatable)."),
    click.option("--backoff-max", type=click.FloatRange(min=0), default=30.0,
                 show_default=True, help="Longest wait between respawns of a crash-looping node."),
    click.option("--crash-limit", type=click.IntRange(min=0), default=10, show_default=True,
                 help="Short runs in a row after which a respawning node is FAILED (0: never)."),
    click.option("--log-max-size", "log_max_size", default="50M", show_default=True,
                 help="Rotate a node's log file past this size (0: never)."),
    click.option("--log-backups", type=click.IntRange(min=0), default=5, show_default=True,
                 help="Rotated log files kept per stream."),
    click.option("--status/--no-status", "status_view", default=None,
                 help="Live status table under the output (default: on a terminal)."),
    click.option("--with-tests", is_flag=True, help="Also run the <test> nodes (test mode)."),
    click.option("--no-rosout", is_flag=True,
                 help="Do not start /rosout with the embedded master (roscore's log "
                      "aggregator: /rosout_agg and rosout.log)."),
]


def run_options(func: Callable[..., Any]) -> Callable[..., Any]:
    """Decorator adding the run-time options of ``orchestra launch``."""
    for option in reversed(_OPTIONS):
        func = option(func)
    return func


def run_plan(plan: Any, options: dict[str, Any]) -> int:
    """Run the plan's nodes under supervision; returns orchestra's exit code."""
    from orchestra.supervise.runner import parse_size
    from orchestra.supervise.runner import run_plan as _run

    options = dict(options)
    if "log_max_size" in options:
        options["log_max_bytes"] = parse_size(options.pop("log_max_size"))
    if options.get("force_screen") and options.get("force_log"):
        from orchestra.errors import OrchestraError

        raise OrchestraError("--screen and --log cannot be used together")
    return _run(plan, options)


@click.command()
@click.option("--json", "as_json", is_flag=True, help="Print the snapshot(s) as JSON.")
@click.option("--socket", "socket_path", default=None, type=click.Path(),
              help="Ask only the launch behind this status socket.")
@click.option("--master", "use_master", is_flag=True,
              help="Ask the launches registered on the master at ROS_MASTER_URI "
                   "(/roslaunch/uris), also those of other users and machines.")
@click.option("--all", "all_launches", is_flag=True,
              help="Every launch of this user on this machine, whatever its master.")
def status(as_json: bool, socket_path: str | None, use_master: bool,
           all_launches: bool) -> int:
    """Show the nodes of the running launch: state, pid, restarts, uptime, CPU%, RSS, and
    why a node is not running.

    By default the launch of this user whose master is at ROS_MASTER_URI answers over its
    local socket (as rosnode/rostopic talk to the ROS_MASTER_URI graph only).
    """
    from orchestra.master import master_uri_from_env
    from orchestra.supervise.status import (
        launches_at,
        launches_on_master,
        query,
        running_launches,
        table_lines,
    )

    uri = master_uri_from_env()
    if socket_path:
        try:
            launches = [query(socket_path)]
        except OSError as exc:
            raise click.ClickException(f"no launch answers at {socket_path}: {exc}") from None
    elif use_master:
        try:
            launches = launches_on_master(uri)
        except OSError as exc:
            raise click.ClickException(str(exc)) from None
    elif all_launches:
        launches = running_launches()
    else:
        launches = launches_at(uri)
    if as_json:
        click.echo(json.dumps(launches if not socket_path else launches[0], indent=1))
        return 0
    if not launches:
        others = 0 if (socket_path or use_master or all_launches) else len(running_launches())
        hint = (f" at {uri} ({others} other launch(es) of yours run on other masters: "
                "orchestra status --all)") if others else ""
        click.echo(f"no running orchestra launch{hint}", err=True)
        return 1
    for i, launch in enumerate(launches):
        if i:
            click.echo()
        files = " ".join(launch.get("launch_files", [])[:1]) or "?"
        click.echo(f"launch {files} (pid {launch['pid']}, master {launch.get('master_uri')})")
        for line in table_lines(launch["nodes"]):
            click.echo(line)
    return 0
