"""``orchestra core``: a standalone master, like roscore.

Serves until Ctrl-C, SIGTERM or a ``shutdown`` XML-RPC call, then exits 0. Like roscore it
puts /run_id, /rosdistro and /rosversion on the fresh parameter server, starts the /rosout
node (supervised, respawned; ``--no-rosout`` leaves it out) and refuses to start when a
master already answers on the port.
"""
from __future__ import annotations

import logging

import click

from orchestra.errors import OrchestraError

log = logging.getLogger(__name__)


class MasterAlreadyRunning(OrchestraError):
    exit_code = 1


@click.command()
@click.option("-p", "--port", type=click.IntRange(0, 65535), default=None,
              help="Port to serve on (default: the port of ROS_MASTER_URI, else 11311).")
@click.option("--host", default=None, metavar="ADDR",
              help="Address to bind (default 127.0.0.1; 0.0.0.0 when ROS_IP/ROS_HOSTNAME "
                   "is set).")
@click.option("--no-rosout", is_flag=True,
              help="Do not start the /rosout node (log aggregation on /rosout_agg).")
def core(port: int | None, host: str | None, no_rosout: bool) -> None:
    """Run a ROS master, parameter server and the rosout node until interrupted."""
    from orchestra.master import (
        bind_address,
        core_params,
        master_is_up,
        master_uri_from_env,
        port_from_uri,
        start_master,
    )

    if port is None:
        port = port_from_uri(master_uri_from_env())
    bind, advertised = bind_address(host)
    probe = f"http://{'127.0.0.1' if bind in ('0.0.0.0', '') else bind}:{port}/"
    if port and master_is_up(probe, timeout=1.0):
        raise MasterAlreadyRunning(
            f"another master is already running at {probe}; stop it first or pick another "
            "port with -p")
    from orchestra.supervise.reaper import Watchdog
    from orchestra.supervise.rosout import serve_core

    watchdog = Watchdog()  # forked first: it must not inherit the master's socket
    result = None
    try:
        handle = start_master(bind, port, advertise=advertised)
        try:
            params = core_params()
            for name, value in params.items():
                handle.params.set(name, value)

            def announce() -> None:
                click.echo(f"ROS_MASTER_URI={handle.uri}")
                click.echo(f"setting /run_id to {params['/run_id']}")
                click.echo("master ready (Ctrl-C to stop)")

            result = serve_core(handle, params["/run_id"], not no_rosout, watchdog,
                                lambda text: click.echo(text, err=True), announce)
        finally:
            handle.shutdown(result.reason if result is not None else "core stopped")
    finally:
        watchdog.close()
    click.echo(f"master stopped ({handle.shutdown_reason})", err=True)
    if result.exit_code:
        click.get_current_context().exit(result.exit_code)
