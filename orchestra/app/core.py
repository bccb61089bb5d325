"""``orchestra core``: a standalone master plus roscore's /rosout, like roscore.

Serves until Ctrl-C, SIGTERM or a ``shutdown`` XML-RPC call. Like roscore it puts /run_id,
/rosdistro and /rosversion on the fresh parameter server, starts the /rosout node
(supervised, respawned; ``--no-rosout`` leaves it out) and refuses to start when a master
already answers on the port.
"""
from __future__ import annotations

import threading
from collections.abc import Callable

from orchestra.errors import OrchestraError
from orchestra.master import (
    MasterHandle,
    bind_address,
    core_params,
    master_is_up,
    master_uri_from_env,
    port_from_uri,
    start_master,
)
from orchestra.supervise.output import prepare_run_log_dir
from orchestra.supervise.reaper import Watchdog
from orchestra.supervise.rosout import core_nodes, resolve_core_executables
from orchestra.supervise.specs import SpecOptions, run_specs
from orchestra.supervise.supervisor import RunResult, Supervisor


class MasterAlreadyRunning(OrchestraError):
    exit_code = 1


def serve_core(handle: MasterHandle, run_id: str, rosout: bool, watchdog: Watchdog,
               report: Callable[[str], None],
               announce: Callable[[], None] | None = None) -> RunResult:
    """After the master is up: supervise the core nodes until a signal or the master's own
    ``shutdown``; the result's exit code is 1 when a core node ended FAILED.

    The supervisor's loop owns SIGINT/SIGTERM/SIGHUP, so a Ctrl-C stops /rosout first (it
    still unregisters from the live master), then the caller stops the master. ``announce``
    runs once those signals are handled, before /rosout is spawned.
    """
    nodes = core_nodes((), embedded_master=True, enabled=rosout)
    executables = resolve_core_executables(nodes, report)
    nodes = [node for node in nodes if node.full_name in executables]
    run_dir = prepare_run_log_dir(run_id) if nodes else None
    specs = run_specs(nodes, [], executables, handle.uri, run_dir, SpecOptions()) if nodes else []
    supervisor = Supervisor(specs, log_dir=run_dir, watchdog=watchdog, keep_alive=True)

    def stop_with_master() -> None:
        handle.wait()
        supervisor.loop.call_threadsafe(
            lambda: supervisor.request_stop(f"master stopped ({handle.shutdown_reason})"))

    threading.Thread(target=stop_with_master, name="core: master watch", daemon=True).start()

    def before_start() -> None:
        if announce is not None:
            announce()
        if run_dir is not None:
            report(f"logging to {run_dir}")

    result = supervisor.run(before_start=before_start)
    if result.failed:
        report(f"orchestra: error: {result.reason}")
    return result


def serve_core_until_stopped(port: int | None, host: str | None, rosout: bool,
                             out: Callable[[str], None], report: Callable[[str], None]) -> int:
    """The whole ``orchestra core`` run; its exit code. ``out`` gets the announcement lines
    (ROS_MASTER_URI=...), ``report`` the progress messages."""
    if port is None:
        port = port_from_uri(master_uri_from_env())
    bind, advertised = bind_address(host)
    probe = f"http://{'127.0.0.1' if bind in ('0.0.0.0', '') else bind}:{port}/"
    if port and master_is_up(probe, timeout=1.0):
        raise MasterAlreadyRunning(
            f"another master is already running at {probe}; stop it first or pick another "
            "port with -p")
    watchdog = Watchdog()  # forked first: it must not inherit the master's socket
    result = None
    try:
        handle = start_master(bind, port, advertise=advertised)
        try:
            params = core_params()
            for name, value in params.items():
                handle.params.set(name, value)

            def announce() -> None:
                out(f"ROS_MASTER_URI={handle.uri}")
                out(f"setting /run_id to {params['/run_id']}")
                out("master ready (Ctrl-C to stop)")

            result = serve_core(handle, params["/run_id"], rosout, watchdog, report, announce)
        finally:
            handle.shutdown(result.reason if result is not None else "core stopped")
    finally:
        watchdog.close()
    report(f"master stopped ({handle.shutdown_reason})")
    return result.exit_code
