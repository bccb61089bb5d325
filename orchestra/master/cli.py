"""``orchestra core``: a standalone master, like roscore.

Serves until Ctrl-C, SIGTERM or a ``shutdown`` XML-RPC call, then exits 0. Like roscore it
puts /run_id, /rosdistro and /rosversion on the fresh parameter server and refuses to start
when a master already answers on the port.
"""
from __future__ import annotations

import logging
import signal
import threading

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
def core(port: int | None, host: str | None) -> None:
    """Run a ROS master and parameter server until interrupted."""
    from orchestra.master import (bind_address, core_params, master_is_up,
                                  master_uri_from_env, port_from_uri, start_master)

    if port is None:
        port = port_from_uri(master_uri_from_env())
    bind, advertised = bind_address(host)
    probe = f"http://{'127.0.0.1' if bind in ('0.0.0.0', '') else bind}:{port}/"
    if port and master_is_up(probe, timeout=1.0):
        raise MasterAlreadyRunning(
            f"another master is already running at {probe}; stop it first or pick another "
            "port with -p")
    handle = start_master(bind, port, advertise=advertised)
    params = core_params()
    for name, value in params.items():
        handle.params.set(name, value)

    def stop(signum: int, frame: object) -> None:
        threading.Thread(target=handle.shutdown, args=(signal.Signals(signum).name,),
                         daemon=True).start()

    signal.signal(signal.SIGTERM, stop)
    signal.signal(signal.SIGINT, stop)
    click.echo(f"ROS_MASTER_URI={handle.uri}")
    click.echo(f"setting /run_id to {params['/run_id']}")
    click.echo("master ready (Ctrl-C to stop)")
    while not handle.wait(0.5):
        pass
    click.echo(f"master stopped ({handle.shutdown_reason})", err=True)
