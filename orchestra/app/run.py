"""``LaunchRun``: one run of a plan — master, parameters, rosout, supervisor, status, UI.

The single composition behind ``orchestra launch`` (``serve()``: in the foreground, owning
the stop signals) and the Python API (``start()``: the supervisor's loop in a thread, the
caller keeps control). Order matters for "nothing half-started": everything that can be the
user's fault (duplicate names, unknown executables, remote machines, unwritable dumps) is
checked before the master is touched or any process is spawned. Then, like roslaunch: master,
/run_id, ``<rosparam>`` actions, clear + upload the parameters, /rosout first when the master
is ours, then the plan's nodes.

Calls from other threads (kill, restart, process) go through the loop's ``call_threadsafe``
so the supervisor is only ever touched from its own thread.
"""
from __future__ import annotations

import concurrent.futures
import itertools
import logging
import os
import signal
import sys
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, TypeVar

from orchestra.app.machines import master_warnings, open_remote, remote_specs, split_remote
from orchestra.app.master import (
    MasterConnection,
    check_param_actions,
    connect_master,
    delete_param,
    is_loopback_uri,
    run_param_actions,
    set_param,
    upload,
)
from orchestra.app.options import RunOptions
from orchestra.launch.plan import LaunchPlan, Node
from orchestra.rpc import TRANSPORT_ERRORS, proxy
from orchestra.supervise import control
from orchestra.supervise.output import Screen, prepare_run_log_dir
from orchestra.supervise.process import ManagedProcess, State
from orchestra.supervise.reaper import Watchdog
from orchestra.supervise.rosout import core_nodes, resolve_core_executables
from orchestra.supervise.rpc import LaunchRPCServer, uris_param
from orchestra.supervise.specs import check_unique_names, resolve_executables, run_specs
from orchestra.supervise.status import LiveView, ProcessStats, StatusServer, runtime_dir, snapshot
from orchestra.supervise.supervisor import RunResult, Supervisor

if TYPE_CHECKING:
    from orchestra.remote.session import RemoteSession

logger = logging.getLogger(__name__)

T = TypeVar("T")

_RUNS = itertools.count()     # status socket names of several runs in one process


@dataclass(frozen=True)
class ProcessInfo:
    """One process of a run at one moment (a copy: it does not change afterwards)."""

    name: str
    state: State
    pid: int | None
    restarts: int
    exit_code: int | None
    reason: str

    @classmethod
    def of(cls, proc: ManagedProcess) -> ProcessInfo:
        return cls(proc.spec.name, proc.state, proc.pid, proc.restarts, proc.exit_code,
                   proc.reason)


@dataclass
class RunReport:
    """How a run ended: orchestra's exit code, why, and every process's last state."""

    exit_code: int
    reason: str
    failed: list[str] = field(default_factory=list)
    processes: dict[str, ProcessInfo] = field(default_factory=dict)

    @property
    def ok(self) -> bool:
        return self.exit_code == 0


class RunEnded(RuntimeError):
    """The run is over (stopped, or a required node ended it): nothing more to ask it."""


def _log_report(text: str) -> None:
    logger.info("%s", text)


class LaunchRun:
    """A plan brought up under supervision; see the module docstring.

    ``report`` receives orchestra's one-line messages for the user (the CLI prints them on
    stderr; the API default logs them). Node output goes to ``screen``. ``announce`` is
    called once the plan passed every check and the master is up, before any node starts,
    with the nodes to run here, the remote ones and the master URI (the CLI prints
    roslaunch's SUMMARY there).
    """

    def __init__(self, plan: LaunchPlan, options: RunOptions | None = None,
                 report: Callable[[str], None] | None = None, screen: Screen | None = None,
                 announce: Callable[[list[Node], list[Node], str], None] | None = None):
        self.plan = plan
        self.options = options or RunOptions()
        self._report = report or _log_report
        self._screen = screen
        self._announce = announce
        self.master: MasterConnection | None = None
        self.log_dir: str | None = None
        self.supervisor: Supervisor | None = None
        self.remote: RemoteSession | None = None     # the run's remote machines, if any
        self.report: RunReport | None = None
        self._watchdog: Watchdog | None = None
        self._thread: threading.Thread | None = None
        self._ended = threading.Event()
        self._closers: list[Callable[[], None]] = []
        self._lock = threading.Lock()
        # calls handed to the loop and not answered yet: answered RunEnded when it ends
        self._pending: set[concurrent.futures.Future[Any]] = set()

    # ------------------------------------------------------------------ life cycle

    def serve(self) -> RunReport:
        """Set up and supervise in this thread until the run ends (``orchestra launch``).

        Owns SIGINT/SIGTERM/SIGHUP while it runs (first: orderly stop, second: kill).
        """
        self._setup()
        return self._supervise(install_signals=True)

    def start(self) -> LaunchRun:
        """Set up and spawn every node; returns then, the run goes on in a thread."""
        if self.supervisor is not None:
            raise RuntimeError("this run was already started")
        self._setup()
        self._thread = threading.Thread(target=self._supervise, args=(False,),
                                        name="orchestra run", daemon=True)
        self._thread.start()
        # the loop runs this only after start_all: every node has been spawned on return
        try:
            self._call(lambda: None)
        except RunEnded:
            pass            # nothing to supervise (no nodes, a reused master): already over
        return self

    def wait(self, timeout: float | None = None) -> RunReport | None:
        """Block until the run ends by itself; None on timeout."""
        if not self._ended.wait(timeout):
            return None
        return self.report

    def stop(self, timeout: float | None = None) -> RunReport:
        """Stop every node (SIGINT, SIGTERM, SIGKILL as their timeouts say) and the master;
        returns when nothing of the run is left."""
        if self.supervisor is None:
            raise RuntimeError("this run was never started")
        if not self._ended.is_set():
            supervisor = self.supervisor
            try:
                supervisor.loop.call_threadsafe(lambda: supervisor.request_stop("stop()"))
            except OSError:
                pass  # the loop closed meanwhile: the run is ending anyway
        if not self._ended.wait(timeout):
            raise TimeoutError(f"the run did not stop within {timeout} s")
        assert self.report is not None
        return self.report

    def kill_all(self) -> None:
        """A second Ctrl-C during stop(): SIGKILL every process still stopping, no more
        waiting for their timeouts (as ``orchestra launch`` does)."""
        supervisor = self._started()
        if not self._ended.is_set():
            try:
                supervisor.loop.call_threadsafe(supervisor.kill_all)
            except OSError:
                pass  # the loop closed meanwhile: the run is ending anyway

    def __enter__(self) -> LaunchRun:
        if self.supervisor is None:
            self.start()
        return self

    def __exit__(self, *exc: object) -> None:
        if self.supervisor is not None:
            self.stop()

    # ------------------------------------------------------------------ what is running

    @property
    def master_uri(self) -> str:
        if self.master is None:
            raise RuntimeError("the run is not started")
        return self.master.uri

    @property
    def run_id(self) -> str:
        if self.master is None:
            raise RuntimeError("the run is not started")
        return self.master.run_id

    @property
    def nodes(self) -> list[str]:
        """Full names of the run's processes, in start order (/rosout first when ours)."""
        if self.supervisor is None:
            return []
        return [proc.spec.name for proc in self.supervisor.procs]

    @property
    def running(self) -> bool:
        return self.supervisor is not None and not self._ended.is_set()

    def process(self, name: str) -> ProcessInfo:
        """The current state of one process (KeyError for a name not in the run)."""
        supervisor = self._started()
        if self._ended.is_set():
            return ProcessInfo.of(supervisor.by_name(_absolute(name)))
        return self._call(lambda: ProcessInfo.of(supervisor.by_name(_absolute(name))))

    def processes(self) -> dict[str, ProcessInfo]:
        supervisor = self._started()
        if self._ended.is_set():
            return {p.spec.name: ProcessInfo.of(p) for p in supervisor.procs}
        return self._call(lambda: {p.spec.name: ProcessInfo.of(p) for p in supervisor.procs})

    # ------------------------------------------------------------------ control

    def kill(self, name: str, sig: int = signal.SIGKILL) -> str:
        """Send ``sig`` (default SIGKILL) to one node, as a crash would: respawn and
        required rules apply. Returns what happened (``sent SIGKILL to /sim``)."""
        supervisor = self._started()
        return self._call(lambda: supervisor.signal_process(_absolute(name), sig))

    def restart(self, name: str) -> str:
        """Stop one node in order and start it again (or start it, if it had ended)."""
        supervisor = self._started()
        return self._call(lambda: supervisor.restart_process(_absolute(name)))

    def stop_node(self, name: str, force: bool = False) -> str:
        """Stop one node by hand (STOPPED: not respawned; a required one needs ``force``)."""
        supervisor = self._started()
        return self._call(lambda: supervisor.stop_process(_absolute(name), force))

    def start_node(self, name: str) -> str:
        """Start one node that is not running (stopped by hand, ended or failed)."""
        supervisor = self._started()
        return self._call(lambda: supervisor.start_process(_absolute(name)))

    def wait_for(self, topic: str | None = None, service: str | None = None,
                 node: str | None = None, param: str | None = None,
                 timeout: float = 30.0) -> None:
        """Block until every named thing exists on the run's master: a topic with a
        publisher, a service, a registered node, a parameter. TimeoutError (naming what is
        missing) after ``timeout`` s; RunEnded when the run ends meanwhile."""
        deadline = time.monotonic() + timeout
        with proxy(self.master_uri, timeout=5.0) as master:
            while True:
                missing = _missing(master, topic, service, node, param)
                if not missing:
                    return
                if self._ended.is_set():
                    raise RunEnded(f"the run ended ({self.report.reason if self.report else ''}) "
                                   f"before {missing} appeared")
                if time.monotonic() >= deadline:
                    raise TimeoutError(f"{missing} did not appear on {self.master_uri} "
                                       f"within {timeout} s")
                self._ended.wait(0.05)

    # ------------------------------------------------------------------ internals

    def _started(self) -> Supervisor:
        if self.supervisor is None:
            raise RuntimeError("the run is not started")
        return self.supervisor

    def _call(self, func: Callable[[], T], timeout: float = 30.0) -> T:
        """Run ``func`` in the supervisor's thread and return its result (or raise its error)."""
        supervisor = self._started()
        if self._thread is None or threading.current_thread() is self._thread:
            return func()
        if self._ended.is_set():
            raise RunEnded("the run is over")
        future: concurrent.futures.Future[T] = concurrent.futures.Future()

        def call() -> None:
            if not future.set_running_or_notify_cancel():
                return
            try:
                future.set_result(func())
            except BaseException as exc:  # noqa: BLE001 - handed to the caller
                future.set_exception(exc)

        with self._lock:
            if self._ended.is_set():
                raise RunEnded("the run is over")
            self._pending.add(future)
        try:
            supervisor.loop.call_threadsafe(call)
            done, _ = concurrent.futures.wait([future], timeout=timeout)
        finally:
            with self._lock:
                self._pending.discard(future)
        if not done:
            raise TimeoutError("the supervisor did not answer")
        if future.cancelled():
            raise RunEnded("the run is over")
        return future.result()

    def _environ(self) -> dict[str, str]:
        env = dict(os.environ)
        if self.options.ros_home:
            env["ROS_HOME"] = self.options.ros_home
            env.pop("ROS_LOG_DIR", None)
        if self.options.log_root:
            env["ROS_LOG_DIR"] = self.options.log_root
        return env

    def _setup(self) -> None:
        opts = self.options
        plan = self.plan
        nodes = list(plan.nodes) + (list(plan.tests) if opts.with_tests else [])
        # --- everything that may be the user's fault, before anything starts
        check_unique_names(nodes)
        nodes, remote = split_remote(plan, nodes)
        executables = resolve_executables(nodes)
        check_param_actions(plan)

        environ = self._environ()
        self._watchdog = watchdog = Watchdog()  # forked first: not inheriting the master's socket
        try:
            session = None
            if remote and not opts.local:   # all-or-nothing: every machine ready, or exit 2
                self.remote = session = open_remote(plan, remote, watchdog)
                self._closers.append(session.close)
            self.master = master = connect_master(opts, self._report,
                                                  public=session is not None)
            if self._announce is not None:
                self._announce(nodes, [] if opts.local else remote, master.uri)
            self.log_dir = prepare_run_log_dir(master.run_id, environ)
            run_param_actions(plan, master.uri, self._report)
            upload(plan, master)
            core = core_nodes(nodes, master.embedded, enabled=not opts.no_rosout)
            core_exes = resolve_core_executables(core, self._report)
            core = [node for node in core if node.full_name in core_exes]
            specs = run_specs(core, nodes, {**executables, **core_exes}, master.uri,
                              self.log_dir, opts, environ)
            if session is not None:
                specs += remote_specs(session, remote, master.uri, master.run_id,
                                      self.log_dir, opts)
                for warning in master_warnings(master.uri, master.embedded):
                    self._report(warning)
            screen = self._screen or Screen()
            if not opts.disable_title and plan.files_loaded:
                _set_title(" ".join(plan.files_loaded[:1]) + f" {master.uri}")
            self._report(f"logging to {self.log_dir}")
            for node in remote if opts.local else ():
                self._report(f"--local: not starting remote node {node.full_name} "
                             f"(machine {node.machine_name})")
            self.supervisor = Supervisor(specs, opts.restart_policy(), screen=screen,
                                         log_dir=self.log_dir, watchdog=self._watchdog,
                                         log_max_bytes=opts.log_max_bytes,
                                         log_backups=opts.log_backups,
                                         keep_alive=master.embedded)
            self._serve_status(screen)
        except BaseException:
            self._teardown()
            raise

    def _serve_status(self, screen: Screen) -> None:
        """The status socket, the launch's XML-RPC server on the master, the live view."""
        supervisor = self.supervisor
        master = self.master
        assert supervisor is not None and master is not None
        stats = ProcessStats()
        info = {"run_id": master.run_id, "master_uri": master.uri,
                "launch_files": list(self.plan.files_loaded), "log_dir": self.log_dir}

        def make_snapshot() -> dict[str, Any]:
            document = snapshot(supervisor.procs, stats, info)
            # remote nodes: their pid/CPU/memory on their machine, not their local client's
            return self.remote.annotate(document) if self.remote is not None else document

        number = next(_RUNS)
        path = os.path.join(runtime_dir(), f"{os.getpid()}{f'-{number}' if number else ''}.sock")
        try:
            server = StatusServer(supervisor.loop, make_snapshot, path,
                                  control=lambda request: control.handle(supervisor, request))
            self._closers.append(server.close)
        except OSError as exc:       # status is a convenience: never a reason not to run
            logger.warning("no status socket (orchestra status will not see this launch): %s",
                           exc)
        rpc = LaunchRPCServer(supervisor.loop, supervisor.procs, make_snapshot,
                              loopback=is_loopback_uri(master.uri))
        self._closers.append(rpc.close)
        uris_key = uris_param(rpc.host, rpc.port)
        set_param(master.uri, uris_key, rpc.uri)
        if not master.embedded:         # roslaunch leaves it behind; we do not
            self._closers.append(lambda: delete_param(master.uri, uris_key))
        opts = self.options
        view_on = opts.status_view if opts.status_view is not None else screen.out.isatty()
        if opts.ui:     # only then: the interactive view (and rich) is not imported
            from orchestra.supervise.interactive import InteractiveView, terminal_ok
        if opts.ui and terminal_ok(sys.stdin, screen.out):
            ui = InteractiveView(supervisor.loop, supervisor, screen, make_snapshot,
                                 sys.stdin.fileno())
            supervisor.on_change = ui.changed
            supervisor.loop.call_later(0, ui.start)
            self._closers.append(ui.close)
        elif opts.ui:
            self._report("--ui: stdin and stdout are not both a terminal; plain output")
        elif view_on:
            view = LiveView(supervisor.loop, screen, make_snapshot)
            supervisor.on_change = view.changed
            supervisor.loop.call_later(0, view.start)
            self._closers.append(view.close)

    def _supervise(self, install_signals: bool) -> RunReport:
        supervisor = self.supervisor
        assert supervisor is not None
        result = RunResult(1, "internal error")
        try:
            result = supervisor.run(install_signals=install_signals)
        except BaseException as exc:
            logger.exception("the run failed")
            result = RunResult(1, f"internal error: {exc}")
            raise
        finally:
            self._teardown()
            self.report = RunReport(result.exit_code, result.reason, list(result.failed),
                                    {p.spec.name: ProcessInfo.of(p) for p in supervisor.procs})
            with self._lock:
                self._ended.set()
                pending, self._pending = self._pending, set()
            for future in pending:        # not run by the loop: the caller gets RunEnded
                if future.cancel():
                    future.set_running_or_notify_cancel()   # wakes concurrent.futures.wait
        return self.report

    def _teardown(self) -> None:
        closers, self._closers = self._closers, []
        for close in reversed(closers):
            try:
                close()
            except Exception:  # noqa: BLE001 - close the rest regardless
                logger.exception("while closing the run")
        if self.master is not None:
            self.master.close()
        if self._watchdog is not None:
            self._watchdog.close()
            self._watchdog = None


def _absolute(name: str) -> str:
    return name if name.startswith("/") else "/" + name


def _missing(master: Any, topic: str | None, service: str | None, node: str | None,
             param: str | None) -> str:
    """The first of the wanted names the master does not know yet ('' when all are there)."""
    caller = "/orchestra_wait_for"
    try:
        if topic is not None:
            code, _, state = master.getSystemState(caller)
            publishers = dict((name, nodes) for name, nodes in state[0]) if code == 1 else {}
            if not publishers.get(_absolute(topic)):
                return f"topic {_absolute(topic)}"
        if service is not None and master.lookupService(caller, _absolute(service))[0] != 1:
            return f"service {_absolute(service)}"
        if node is not None and master.lookupNode(caller, _absolute(node))[0] != 1:
            return f"node {_absolute(node)}"
        if param is not None and master.hasParam(caller, _absolute(param))[2] is not True:
            return f"parameter {_absolute(param)}"
    except TRANSPORT_ERRORS as exc:
        return f"the master ({exc})"
    return ""


def _set_title(title: str) -> None:
    if sys.stdout.isatty():
        sys.stdout.write(f"\x1b]2;{title}\x07")
        sys.stdout.flush()

