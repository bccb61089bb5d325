"""``orchestra node``: node/cli's graph commands plus stop, start, restart and signal.

The four control commands drive the launches' control sockets (supervise/status.py and
supervise/control.py), a layer above node/, so they are composed here, at the top: node/
keeps the commands that only talk to the master and the nodes (list, info, kill, ping,
cleanup, loggers), and this group is node/cli's group with the control commands added.
"""
from __future__ import annotations

import time

import click

from orchestra.completion import complete_node_names
from orchestra.errors import OrchestraError
from orchestra.node import introspect
from orchestra.node.cli import CommandFailed, graph_name
from orchestra.node.cli import node as graph_node
from orchestra.rpc import master_uri_from_env

# a copy of the command table: node/cli's own group stays as it is
node = click.Group(name=graph_node.name, commands=dict(graph_node.commands),
                   help=graph_node.help)


class _Unknown(OrchestraError):
    """Names matching no node of the launch nor of the graph: a user mistake (exit 2)."""


def _control(op: str, names: tuple[str, ...], force: bool = False, sig: str = "",
             timeout: float = 30.0) -> None:
    """Ask the launches at ROS_MASTER_URI to act on NAMES, then wait until they settled.

    Several orchestra launches may share one master (``orchestra core`` and two launch
    files): each NAME goes to every launch it matches nodes of. Names no launch knows but
    the master does (nodes started by something else) are stopped the way ``node kill``
    does; anything else is unknown: exit 2, nothing done.
    """
    from orchestra.suggest import did_you_mean
    from orchestra.supervise.control import matches
    from orchestra.supervise.status import launches_at, request

    uri = master_uri_from_env()
    launches = launches_at(uri)
    ours = [n["name"] for launch in launches for n in launch["nodes"]]
    plan = [(launch, [n for n in names if matches(n, [x["name"] for x in launch["nodes"]])])
            for launch in launches]
    foreign = [n for n in names if not matches(n, ours)]
    if foreign:
        graph: list[str] = []
        if op == "stop":
            try:
                graph = introspect.system_state(uri).nodes
            except (OSError, introspect.GraphError, OrchestraError):
                graph = []
        missing = [n for n in foreign if graph_name(n) not in graph]
        if missing:
            where = "this launch" if launches else f"any orchestra launch at {uri}"
            raise _Unknown("\n".join(f"no node {graph_name(n)} in {where}"
                                      f"{did_you_mean(graph_name(n), ours + graph)}"
                                      for n in missing))
    for launch, mine in plan:
        if not mine:
            continue
        before = {n["name"]: n for n in launch["nodes"]}
        body: dict = {"op": op, "names": mine, "force": force}
        if sig:
            body["signal"] = sig
        try:
            answer = request(launch["socket"], body)
        except (OSError, ValueError) as exc:
            raise CommandFailed(f"the launch did not answer: {exc}") from None
        if not answer.get("ok"):
            raise (_Unknown if answer.get("unknown") else CommandFailed)(
                str(answer.get("error")))
        if op != "signal":
            _wait_settled(launch["socket"], [n for n, _ in answer["done"]], before, timeout)
    for name in foreign:
        click.echo(f"killing {graph_name(name)} (not started by orchestra: asked to shut down)")
        try:
            introspect.kill_node(uri, graph_name(name))
        except introspect.GraphError as exc:
            raise CommandFailed(str(exc)) from None


def _wait_settled(path: str, names: list[str], before: dict, timeout: float) -> None:
    """Poll the launch until none of ``names`` is STOPPING/STARTING; print where each ended."""
    from orchestra.supervise.status import query

    deadline = time.monotonic() + timeout
    while True:
        nodes = {n["name"]: n for n in query(path)["nodes"]}
        busy = [n for n in names if nodes[n]["state"] in ("STOPPING", "STARTING")]
        if not busy or time.monotonic() > deadline:
            break
        time.sleep(0.05)
    for name in names:
        now, old = nodes[name], before.get(name, {})
        pid = f" (pid {old.get('pid')} -> {now['pid']})" if old.get("pid") and now["pid"] \
            else (f" (pid {now['pid']})" if now["pid"] else "")
        click.echo(f"{name}: {now['state']}{pid}" + (f" - {now['reason']}" if now["reason"]
                                                      and now["state"] != "RUNNING" else ""))
    if busy:
        raise CommandFailed(f"still {nodes[busy[0]]['state']} after {timeout:g} s: "
                            + ", ".join(busy))


_FORCE = click.option("-f", "--force", is_flag=True,
                      help="Also stop required nodes (whose end otherwise stops the launch).")
_TIMEOUT = click.option("--timeout", type=click.FloatRange(min=0), default=30.0,
                        show_default=True, help="Seconds to wait for the nodes to settle.")


@node.command("stop")
@click.argument("names", nargs=-1, required=True, shell_complete=complete_node_names)
@_FORCE
@_TIMEOUT
def node_stop(names: tuple[str, ...], force: bool, timeout: float) -> None:
    """Stop NAMES of the launch at ROS_MASTER_URI; the rest keeps running.

    A NAME is a node, a namespace (every node below it) or a glob (/cam*). A stopped node is
    STOPPED until started again. Nodes not started by orchestra are asked to shut down, as
    ``node kill`` does.
    """
    _control("stop", names, force=force, timeout=timeout)


@node.command("start")
@click.argument("names", nargs=-1, required=True, shell_complete=complete_node_names)
@_TIMEOUT
def node_start(names: tuple[str, ...], timeout: float) -> None:
    """Start NAMES again (stopped by hand, ended or failed) in the launch at ROS_MASTER_URI."""
    _control("start", names, timeout=timeout)


@node.command("restart")
@click.argument("names", nargs=-1, required=True, shell_complete=complete_node_names)
@_TIMEOUT
def node_restart(names: tuple[str, ...], timeout: float) -> None:
    """Stop NAMES (SIGINT, then SIGTERM, SIGKILL) and start them again; the rest runs on."""
    _control("restart", names, timeout=timeout)


@node.command("signal")
@click.argument("sig", metavar="SIGNAL")
@click.argument("names", nargs=-1, required=True, shell_complete=complete_node_names)
def node_signal(sig: str, names: tuple[str, ...]) -> None:
    """Send SIGNAL (USR1, SIGHUP, 10...) to NAMES of the launch at ROS_MASTER_URI."""
    _control("signal", names, sig=sig)
    click.echo(f"sent {sig} to {', '.join(names)}")

