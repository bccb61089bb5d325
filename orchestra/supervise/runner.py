"""``orchestra launch`` at run time: plan -> master + params -> supervised processes.

The order matters for "nothing half-started": everything that can be the user's fault
(unknown executables, remote machines, bad args) is checked before the master is touched
or any process is spawned. Then, like roslaunch: use the master at ROS_MASTER_URI when one
answers (or wait for it with ``--wait``), else start the embedded one; set /run_id, clear
and upload the parameters, and start the nodes (after /rosout when the master is ours, as
roslaunch starts roscore.xml's node: see rosout.py).
"""
from __future__ import annotations

import logging
import os
import sys
import time
import urllib.parse
import uuid
import xmlrpc.client
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from typing import Any

import click

from orchestra.errors import Location, OrchestraError
from orchestra.launch.plan import LaunchPlan, Node
from orchestra.ros1.activation import layer_env
from orchestra.supervise.command import (
    find_node_executable,
    node_argv,
    node_cwd,
    node_env,
    path_with_interpreter,
    ros_home,
)
from orchestra.supervise.output import Screen, prepare_run_log_dir
from orchestra.supervise.process import Limits, OutputMode, ProcessSpec, RestartPolicy

logger = logging.getLogger(__name__)

LOCAL_NAMES = {"localhost", "127.0.0.1", "::1", "localhost.localdomain", "ip6-localhost"}


@dataclass(frozen=True)
class RunOptions:
    """The run-time flags of ``orchestra launch`` (see cli.run_options for their help)."""

    force_screen: bool = False
    force_log: bool = False
    wait: bool = False
    all_required: bool = False
    local: bool = False
    disable_title: bool = False
    port: int | None = None
    run_id: str | None = None
    sigint_timeout: float = 15.0
    sigterm_timeout: float = 2.0
    node_timeouts: Mapping[str, tuple[float | None, float | None]] = field(default_factory=dict)
    backoff_max: float = 30.0
    crash_limit: int = 10
    log_max_bytes: int = 0
    log_backups: int = 5
    status_view: bool | None = None
    with_tests: bool = False
    no_rosout: bool = False

    @classmethod
    def from_kwargs(cls, options: Mapping[str, Any]) -> RunOptions:
        known = {f for f in cls.__dataclass_fields__}
        values = {k: v for k, v in options.items() if k in known and v is not None}
        if "node_timeouts" in values and not isinstance(values["node_timeouts"], Mapping):
            values["node_timeouts"] = parse_node_timeouts(values["node_timeouts"])
        return cls(**values)


def parse_node_timeouts(items: Any) -> dict[str, tuple[float | None, float | None]]:
    """``/node=SIGINT[,SIGTERM]`` words -> {"/node": (sigint, sigterm)}."""
    result: dict[str, tuple[float | None, float | None]] = {}
    for item in items or ():
        name, sep, spec = str(item).partition("=")
        parts = spec.split(",")
        try:
            if not sep or not name or len(parts) > 2:
                raise ValueError
            sigint = float(parts[0]) if parts[0] else None
            sigterm = float(parts[1]) if len(parts) > 1 and parts[1] else None
            if (sigint is not None and sigint < 0) or (sigterm is not None and sigterm < 0):
                raise ValueError
        except ValueError:
            raise OrchestraError(f"--node-timeout {item!r}: expected NODE=SIGINT_SECONDS"
                                 "[,SIGTERM_SECONDS], e.g. /camera=30,5") from None
        result[name if name.startswith("/") else "/" + name] = (sigint, sigterm)
    return result


def parse_size(text: str | int | None) -> int:
    """``100M`` / ``512K`` / ``1G`` / bytes -> bytes (0 = no rotation)."""
    if text is None:
        return 0
    if isinstance(text, int):
        return text
    value = text.strip().upper()
    scale = 1
    if value and value[-1] in "KMG":
        scale = 1024 ** ("KMG".index(value[-1]) + 1)
        value = value[:-1]
    try:
        size = int(float(value) * scale)
    except ValueError:
        raise OrchestraError(f"--log-max-size {text!r}: expected a size like 100M") from None
    if size < 0:
        raise OrchestraError(f"--log-max-size {text!r}: must not be negative")
    return size


def _location(node: Node) -> Location | None:
    return Location(node.filename, node.line) if node.filename else None


def split_remote(plan: LaunchPlan, nodes: list[Node]) -> tuple[list[Node], list[Node]]:
    """(nodes to run here, nodes of remote machines), split as roslaunch splits them."""
    from orchestra.remote.locality import UnresolvableAddress, is_local_machine

    here: list[Node] = []
    remote: list[Node] = []
    verdicts: dict[str, bool] = {}
    for node in nodes:
        machine = plan.machines.get(node.machine_name or "")
        if machine is None or not node.machine_name:
            here.append(node)
            continue
        if machine.name not in verdicts:
            try:
                verdicts[machine.name] = is_local_machine(machine.address, machine.user)
            except UnresolvableAddress:
                raise OrchestraError(f"cannot resolve host address for machine "
                                     f"'{machine.name}' ({machine.address})",
                                     _location(node)) from None
        (here if verdicts[machine.name] else remote).append(node)
    return here, remote


def _check_unique_names(nodes: list[Node]) -> None:
    seen: dict[str, Node] = {}
    for node in nodes:
        first = seen.setdefault(node.full_name, node)
        if first is not node:
            where = f" (first at {_location(first)})" if first.filename else ""
            raise OrchestraError(f"two nodes are named '{node.full_name}'{where}",
                                 _location(node))


def resolve_executables(nodes: list[Node]) -> dict[str, str]:
    """Full name -> executable for every node; ALL problems reported before anything starts."""
    found: dict[str, str] = {}
    errors: list[OrchestraError] = []
    for node in nodes:
        try:
            found[node.full_name] = find_node_executable(node)
        except OrchestraError as exc:
            errors.append(exc)
    if errors:
        first = errors[0]
        more = f" (and {len(errors) - 1} more node(s) like it)" if len(errors) > 1 else ""
        raise OrchestraError(first.message + more, first.location)
    return found


def log_base_name(full_name: str, counter: int) -> str:
    """roslaunch's per-process name for log files: ``robot1-listener-3``."""
    return f"{full_name.lstrip('/').replace('/', '-')}-{counter}"


def output_mode(node: Node, options: RunOptions) -> OutputMode:
    if options.force_screen:
        return OutputMode.SCREEN
    if options.force_log:
        return OutputMode.LOG
    if node.output == "screen":
        return OutputMode.SCREEN
    if node.output == "both":
        return OutputMode.BOTH
    return OutputMode.LOG


def build_specs(nodes: list[Node], executables: Mapping[str, str], master_uri: str,
                run_dir: str, options: RunOptions,
                environ: Mapping[str, str] | None = None) -> list[ProcessSpec]:
    """The ProcessSpec of each node: exactly roslaunch's argv/env/cwd plus our run settings."""
    base = dict(os.environ if environ is None else environ)
    # nodes write to pipes, not a TTY: without this, Python nodes block-buffer their output
    # and the console shows it late (roslaunch leaves screen nodes on the TTY instead)
    base.setdefault("PYTHONUNBUFFERED", "1")
    base["PATH"] = path_with_interpreter(base.get("PATH", ""), sys.executable)
    base.update(layer_env(base))   # rospy & co. for Python nodes without ROS (ros1/activation)
    specs = []
    for counter, node in enumerate(nodes, start=1):
        exe = executables[node.full_name]
        log_name = log_base_name(node.full_name, counter)
        argv = node_argv(node, exe, log_file=os.path.join(run_dir, log_name + ".log"))
        env = dict(base)
        env.update(node_env(node, master_uri))
        sigint, sigterm = options.node_timeouts.get(node.full_name, (None, None))
        if sigint is None and node.stop_timeout is not None:
            # rosmon's stop-timeout: SIGINT, then that many seconds, then killed
            sigint, sigterm = node.stop_timeout, 0.0 if sigterm is None else sigterm
        specs.append(ProcessSpec(
            name=node.full_name, argv=tuple(argv), env=env,
            cwd=node_cwd(node, exe, base),
            respawn=node.respawn, respawn_delay=node.respawn_delay,
            required=node.required or options.all_required,
            output=output_mode(node, options), log_name=log_name,
            sigint_timeout=options.sigint_timeout if sigint is None else sigint,
            sigterm_timeout=options.sigterm_timeout if sigterm is None else sigterm,
            location=str(_location(node)) if node.filename else None,
            limits=Limits(node.memory_limit, node.cpu_limit, node.enable_coredumps)))
    return specs


def run_specs(core: list[Node], nodes: list[Node], executables: Mapping[str, str],
              master_uri: str, run_dir: str, options: RunOptions) -> list[ProcessSpec]:
    """The specs of a run: roscore's nodes first (so they count from 1, as with roslaunch),
    then the plan's. ``--required`` is about the plan's nodes: a core node respawns rather
    than ending the launch. orchestra's own core nodes start with SIGINT held until they can
    take it (``ProcessSpec.sigint_held``): a launch stopped at once ends them quietly."""
    from orchestra.supervise.rosout import releases_sigint

    specs = build_specs(core + nodes, executables, master_uri, run_dir, options)
    return [replace(spec, required=False,
                    sigint_held=releases_sigint(executables[node.full_name]))
            for node, spec in zip(core, specs, strict=False)] + specs[len(core):]


@dataclass
class MasterConnection:
    uri: str
    handle: Any = None           # the embedded master, when we started it
    run_id: str = ""

    def close(self) -> None:
        if self.handle is not None:
            self.handle.shutdown("launch ended")


def _existing_run_id(uri: str) -> str | None:
    try:
        from orchestra.master.client import proxy

        code, _, value = proxy(uri, timeout=5.0).getParam("/roslaunch", "/run_id")
    except Exception:  # noqa: BLE001 - a master without /run_id is fine
        return None
    return value if code == 1 and isinstance(value, str) else None


def connect_master(options: RunOptions, echo, public: bool = False) -> MasterConnection:
    """Use the master at ROS_MASTER_URI if it answers, wait for it (--wait), or embed one.

    ``public``: other machines must reach an embedded master (the plan has remote nodes),
    so it listens on every interface even when ROS_MASTER_URI names localhost.
    """
    from orchestra.master import master_is_up, master_uri_from_env, port_from_uri, start_master

    uri = master_uri_from_env()
    if options.port is not None:
        parts = urllib.parse.urlsplit(uri)
        uri = f"http://{parts.hostname or 'localhost'}:{options.port}/"
    if master_is_up(uri):
        run_id = _existing_run_id(uri) or options.run_id or str(uuid.uuid1())
        return MasterConnection(uri, None, run_id)
    if options.wait:
        echo(f"waiting for the master at {uri} ...")
        while not master_is_up(uri):
            time.sleep(0.2)
        run_id = _existing_run_id(uri) or options.run_id or str(uuid.uuid1())
        return MasterConnection(uri, None, run_id)
    host = urllib.parse.urlsplit(uri).hostname or "localhost"
    loopback = host in LOCAL_NAMES or host.startswith("127.")
    bind = "127.0.0.1" if loopback and not public else "0.0.0.0"
    handle = start_master(bind, port_from_uri(uri), advertise=host)
    echo(f"started embedded master at {handle.uri}")
    return MasterConnection(handle.uri, handle, options.run_id or str(uuid.uuid1()))


def upload(plan: LaunchPlan, master: MasterConnection) -> None:
    from orchestra.master import core_params, upload_params

    params: dict[str, Any] = {}
    if master.handle is not None:
        params.update(core_params(master.run_id))
    params.update(plan.params)
    params["/run_id"] = master.run_id
    upload_params(master.uri, params, list(plan.clear_params))


def check_param_actions(plan: LaunchPlan) -> None:
    """A ``<rosparam command="dump">`` that cannot write its file, refused before anything
    starts (roslaunch only fails when it gets there, with the master already up)."""
    for action in plan.param_actions:
        if action.command != "dump":
            continue
        where = Location(action.filename, action.line) if action.filename else None
        if not action.file:
            raise OrchestraError("<rosparam command=\"dump\">: 'file' must be set to dump "
                                 f"[{action.param}] at launch time", where)
        folder = os.path.dirname(os.path.abspath(action.file))
        if not os.path.isdir(folder):
            raise OrchestraError(f"<rosparam command=\"dump\">: cannot write [{action.file}]: "
                                 f"no directory {folder}", where)


def run_param_actions(plan: LaunchPlan, uri: str, echo) -> None:
    """roslaunch's setup phase: every ``<rosparam>`` dump and delete, in document order.

    roslaunch runs them after the master is up and BEFORE clear_params and the upload, so
    a delete clears what an earlier launch left (this launch's params are set afterwards)
    and a dump writes the server as it was before this launch. As there (where ``rosparam``
    runs as a child whose exit status is ignored), a missing parameter or an unwritable file
    is reported and the launch goes on.
    """
    if not plan.param_actions:
        return
    from orchestra.master.client import TRANSPORT_ERRORS, MasterUnreachable, proxy
    from orchestra.params.dump import dump_yaml

    server = proxy(uri, timeout=30.0)
    for action in plan.param_actions:
        where = f"{action.filename}:{action.line}: " if action.filename else ""
        try:
            if action.command == "delete" and action.param == "/":
                code, message, _ = server.setParam("/roslaunch", "/", {})  # rosparam: empty it
            elif action.command == "delete":
                code, message, _ = server.deleteParam("/roslaunch", action.param)
            else:
                code, message, value = server.getParam("/roslaunch", action.param)
        except xmlrpc.client.Fault as exc:
            code, message = -1, exc.faultString
        except TRANSPORT_ERRORS as exc:
            raise MasterUnreachable(f"cannot reach the master at {uri}: {exc}") from None
        if code != 1:
            echo(f"orchestra: warning: {where}rosparam {action.command}: {message}")
            continue
        if action.command == "delete":
            echo(f"rosparam delete {action.param}")
            continue
        try:
            with open(action.file or "", "w", encoding="utf-8") as fh:
                fh.write(dump_yaml(value))
        except OSError as exc:
            echo(f"orchestra: warning: {where}rosparam dump: cannot write "
                 f"[{action.file}]: {exc.strerror}")
            continue
        echo(f"rosparam dump {action.param} -> {action.file}")


def open_remote(plan: LaunchPlan, remote: list[Node], watchdog: Any) -> Any:
    """Connect and check every remote machine of the run (orchestra/remote/session.py)."""
    from orchestra.remote.session import RemoteSession

    session = RemoteSession(dict(plan.machines), remote, mark=watchdog.mark,
                            watch=watchdog.watch)
    session.open()
    return session


def remote_specs(session: Any, remote: list[Node], master: MasterConnection, run_dir: str,
                 options: RunOptions) -> list[ProcessSpec]:
    """Remote nodes' specs: their run settings as local nodes', their command an ssh session."""
    specs = build_specs(remote, {n.full_name: n.type for n in remote}, master.uri, run_dir,
                        options)
    return [replace(spec, cwd=ros_home(), argv=tuple(session.node_argv(
        node, master.uri, master.run_id, spec.log_name or node.name, spec.sigint_timeout,
        spec.sigterm_timeout))) for node, spec in zip(remote, specs, strict=True)]


def _is_loopback_uri(uri: str) -> bool:
    host = urllib.parse.urlsplit(uri).hostname or "localhost"
    return host in LOCAL_NAMES or host.startswith("127.")


def _set_param(uri: str, key: str, value: Any) -> None:
    try:
        from orchestra.master.client import proxy

        proxy(uri, timeout=5.0).setParam("/roslaunch", key, value)
    except Exception as exc:  # noqa: BLE001 - the launch runs without this entry
        logger.warning("cannot set %s on the master: %s", key, exc)


def _delete_param(uri: str, key: str) -> None:
    try:
        from orchestra.master.client import proxy

        proxy(uri, timeout=5.0).deleteParam("/roslaunch", key)
    except Exception as exc:  # noqa: BLE001 - master may be gone already
        logger.debug("cannot delete %s: %s", key, exc)


def _set_title(title: str) -> None:
    if sys.stdout.isatty():
        sys.stdout.write(f"\x1b]2;{title}\x07")
        sys.stdout.flush()


def run_plan(plan: LaunchPlan, options: Mapping[str, Any]) -> int:
    """Run the plan's nodes under supervision until stopped; returns orchestra's exit code."""
    from orchestra.supervise import control
    from orchestra.supervise.reaper import Watchdog
    from orchestra.supervise.rosout import core_nodes, resolve_core_executables
    from orchestra.supervise.rpc import LaunchRPCServer, uris_param
    from orchestra.supervise.status import LiveView, ProcessStats, StatusServer, snapshot
    from orchestra.supervise.supervisor import Supervisor

    opts = RunOptions.from_kwargs(options)
    nodes = list(plan.nodes) + (list(plan.tests) if opts.with_tests else [])
    # --- everything that may be the user's fault, before anything starts
    _check_unique_names(nodes)
    nodes, remote = split_remote(plan, nodes)
    executables = resolve_executables(nodes)
    check_param_actions(plan)

    def echo(text: str) -> None:
        click.echo(text, err=True)

    watchdog = Watchdog()  # forked first: it must not inherit the master's socket
    master = None
    session = None
    try:
        if remote and not opts.local:     # all-or-nothing: every machine ready, or exit 2
            session = open_remote(plan, remote, watchdog)
        master = connect_master(opts, echo, public=session is not None)
        run_dir = prepare_run_log_dir(master.run_id)
        run_param_actions(plan, master.uri, echo)
        upload(plan, master)
        core = core_nodes(nodes, master.handle is not None, enabled=not opts.no_rosout)
        core_exes = resolve_core_executables(core, echo)
        core = [node for node in core if node.full_name in core_exes]
        specs = run_specs(core, nodes, {**executables, **core_exes}, master.uri, run_dir,
                          opts)
        if session is not None:
            specs += remote_specs(session, remote, master, run_dir, opts)
        screen = Screen()
        if not opts.disable_title and plan.files_loaded:
            _set_title(" ".join(plan.files_loaded[:1]) + f" {master.uri}")
        echo(f"logging to {run_dir}")
        for node in remote if opts.local else ():
            echo(f"--local: not starting remote node {node.full_name} "
                 f"(machine {node.machine_name})")
        supervisor = Supervisor(specs, RestartPolicy(backoff_max=opts.backoff_max,
                                                     crash_limit=opts.crash_limit),
                                screen=screen, log_dir=run_dir, watchdog=watchdog,
                                log_max_bytes=opts.log_max_bytes, log_backups=opts.log_backups,
                                keep_alive=master.handle is not None)
        stats = ProcessStats()
        info = {"run_id": master.run_id, "master_uri": master.uri,
                "launch_files": list(plan.files_loaded), "log_dir": run_dir}

        def make_snapshot() -> dict[str, Any]:
            return snapshot(supervisor.procs, stats, info)

        try:
            server: StatusServer | None = StatusServer(
                supervisor.loop, make_snapshot,
                control=lambda request: control.handle(supervisor, request))
        except OSError as exc:       # status is a convenience: never a reason not to run
            logger.warning("no status socket (orchestra status will not see this launch): %s",
                           exc)
            server = None
        rpc = LaunchRPCServer(supervisor.loop, supervisor.procs, make_snapshot,
                              loopback=_is_loopback_uri(master.uri))
        uris_key = uris_param(rpc.host, rpc.port)
        _set_param(master.uri, uris_key, rpc.uri)
        view_on = opts.status_view if opts.status_view is not None else screen.out.isatty()
        view = LiveView(supervisor.loop, screen, make_snapshot) if view_on else None
        if view is not None:
            supervisor.on_change = view.changed
            supervisor.loop.call_later(0, view.start)
        try:
            result = supervisor.run()
        finally:
            if view is not None:
                view.close()
            if server is not None:
                server.close()
            rpc.close()
            if master.handle is None:       # roslaunch leaves it behind; we do not
                _delete_param(master.uri, uris_key)
    finally:
        if session is not None:
            session.close()
        if master is not None:
            master.close()
        watchdog.close()
    if result.exit_code != 0:
        echo(f"orchestra: error: {result.reason}")
    else:
        echo(f"orchestra: {result.reason}; all processes stopped")
    return result.exit_code
