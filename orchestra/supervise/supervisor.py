"""The Supervisor: starts ProcessSpecs, reacts to every child exit at once, stops them all.

Takes plain ProcessSpecs (no launch plan, no master), so it is tested and benchmarked on its
own. One event loop (``loop.py``) watches, per child, a pidfd (exit) and two pipes (output);
plus the signal wake-up pipe and the status socket. Nothing polls. Where pidfds do not exist
(Linux < 5.3, other Unixes) a thread per child blocks in ``wait`` and hands the exit to the
loop instead.

Exit code of a run: 0 when stopped on request, when every node ended by itself, or when a
required node finished with exit code 0; 1 when a required node died (signal or non-zero
exit) or failed to start, or when any node ended FAILED (the message says which).
"""
from __future__ import annotations

import contextlib
import errno
import functools
import logging
import os
import signal
import subprocess
import threading
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

from orchestra.supervise import stop_signals
from orchestra.supervise.limits import (
    cgroup_unavailable,
    cpu_cgroup,
    explain_exit,
    join_cgroup,
    remove_cgroup,
    rlimit_setup,
)
from orchestra.supervise.loop import EventLoop, Timer
from orchestra.supervise.output import NodeOutput, Screen
from orchestra.supervise.process import (
    TERMINAL,
    ManagedProcess,
    ProcessSpec,
    RestartPolicy,
    State,
    describe_exit,
    restart_delay,
)
from orchestra.supervise.reaper import (
    MARK_VARIABLE,
    Watchdog,
    check_executable,
    child_setup,
    descendants,
    marked_pids,
    new_mark,
    setpriv_prefix,
    signal_group,
)
from orchestra.supervise.spawner import Spawner

logger = logging.getLogger(__name__)

_STOP_SIGNALS = stop_signals.STOP_SIGNALS


@dataclass
class RunResult:
    exit_code: int
    reason: str = ""
    failed: list[str] = field(default_factory=list)


@dataclass
class _Child:
    """OS handles of one running instance of a process."""

    popen: subprocess.Popen
    pidfd: int | None      # None: a waiter thread reports the exit instead
    extra: list[int] = field(default_factory=list)   # descendants outside the process group


class Supervisor:
    """Runs a fixed set of processes until stopped, until all ended, or until a required one died."""

    def __init__(self, specs: Sequence[ProcessSpec], policy: RestartPolicy | None = None,
                 screen: Screen | None = None, log_dir: str | None = None,
                 watchdog: Watchdog | None = None, log_max_bytes: int = 0,
                 log_backups: int = 5, on_change: Callable[[], None] | None = None,
                 pdeathsig: str = "auto", keep_alive: bool = False):
        names = [s.name for s in specs]
        if len(set(names)) != len(names):
            raise ValueError("process names must be unique")
        self.policy = policy or RestartPolicy()
        self.screen = screen or Screen()
        self.log_dir = log_dir
        self.watchdog = watchdog
        # inherited by everything a node starts: how strays that escaped the process tree
        # are found at the end of the run (and by the watchdog if orchestra is killed)
        self.mark = watchdog.mark if watchdog is not None else new_mark()
        self.stray_timeout = 2.0
        self.on_change = on_change
        if pdeathsig in ("auto", "setpriv") and not setpriv_prefix():
            pdeathsig = "preexec"          # same guarantee, slower spawn
        elif pdeathsig == "auto":
            pdeathsig = "setpriv"
        if pdeathsig not in ("setpriv", "preexec", "off"):
            raise ValueError(f"pdeathsig must be auto, setpriv, preexec or off: {pdeathsig!r}")
        self.pdeathsig = pdeathsig
        # keep_alive: run until stopped even when every process ended (orchestra serving its
        # embedded master is like roslaunch having started roscore: it stays up)
        self.keep_alive = keep_alive
        self.loop = EventLoop()
        self.procs = [ManagedProcess(spec, start_index=i) for i, spec in enumerate(specs)]
        self.outputs = {
            p.spec.name: NodeOutput(p.spec.name, p.spec.output, self.screen, log_dir,
                                    p.spec.log_name, log_max_bytes, log_backups)
            for p in self.procs}
        self._children: dict[str, _Child] = {}
        self._timers: dict[str, Timer] = {}
        self._open_pipes = 0
        self.stopping = False
        self.result: RunResult | None = None
        self._stop_reason = ""
        self._signal_count = 0
        self._pid = os.getpid()
        self.started_at = time.monotonic()
        self._cgroups: dict[str, str] = {}
        self._spawner = Spawner()
        self._cgroup_problem = (cgroup_unavailable()
                                if any(s.limits.cpu for s in specs) else None)

    # ------------------------------------------------------------------ public API

    def by_name(self, name: str) -> ManagedProcess:
        for proc in self.procs:
            if proc.spec.name == name:
                return proc
        raise KeyError(name)

    def start_all(self) -> None:
        """Spawn every process; a required one failing to spawn stops everything.

        The commands are vetted in order first: a required process that cannot start
        stops the launch, and nothing after it is spawned (those before it are, and then
        stopped, as when spawning one by one). Then they are spawned together
        (``spawner.py``: one by one, each spawn waited for its child to get a CPU) and
        registered in order, so start order, messages and stop order stay the plan's.
        Where a spawn runs Python in the child (``preexec_fn``: no setpriv, or rlimits),
        everything is spawned one by one in this thread.
        """
        if self.stopping:
            return
        if any(self._preexec(proc.spec) is not None for proc in self.procs):
            for proc in self.procs:
                if self.stopping:
                    break
                self._spawn(proc)
            return
        ready: list[tuple[ManagedProcess, list[str]]] = []
        refused: tuple[ManagedProcess, OSError] | None = None
        vetted: dict[tuple[str, str, str | None], OSError | None] = {}
        for proc in self.procs:
            try:
                ready.append((proc, self._command(proc.spec, vetted)))
            except OSError as exc:
                if proc.spec.required:   # the ones before it start, and are stopped
                    refused = (proc, exc)
                    break
                self._spawn_failed(proc, exc)
        outcomes = self._spawner.run([functools.partial(self._popen, proc.spec, argv)
                                      for proc, argv in ready])
        for (proc, _), outcome in zip(ready, outcomes, strict=True):
            if isinstance(outcome.error, (OSError, subprocess.SubprocessError)):
                self._spawn_failed(proc, outcome.error)
                continue
            if outcome.error is not None:
                raise outcome.error
            assert outcome.value is not None
            if proc.state != State.STARTING:   # marked 'never started' by a stop meanwhile
                proc.transition(State.STARTING, "spawned while the launch was stopping")
            self._started(proc, outcome.value)
            if self.stopping:   # a required one failed to spawn meanwhile: stop this one too
                self._signal_stop(proc, self._stop_reason, [])
        if refused is not None:
            self._spawn_failed(*refused)

    def request_stop(self, reason: str = "stop requested", exit_code: int = 0) -> None:
        """Begin the orderly stop of everything (idempotent; the first reason is kept)."""
        if self.result is None:
            self.result = RunResult(exit_code, reason)
        if self.stopping:
            return
        self.stopping = True
        self._stop_reason = reason
        logger.info("stopping all processes: %s", reason)
        running = [p for p in self.procs if p.state in (State.RUNNING, State.STARTING)
                   and p.spec.name in self._children]
        for proc in self.procs:
            if proc.state == State.BACKOFF:
                self._cancel_timer(proc)
                proc.transition(State.EXITED, "stopped while waiting to respawn")
            elif proc.state == State.STARTING and proc.spec.name not in self._children:
                proc.transition(State.EXITED, "never started")
        trees = descendants(self._children[p.spec.name].popen.pid for p in running)
        for proc in sorted(running, key=lambda p: p.start_index, reverse=True):
            pid = self._children[proc.spec.name].popen.pid
            self._signal_stop(proc, reason, [d for d in trees.get(pid, ()) if _pgid(d) != pid])
        self._changed()

    def kill_all(self) -> None:
        """Second Ctrl-C: no more waiting, SIGKILL every process still stopping."""
        for proc in self.procs:
            if proc.state == State.STOPPING:
                self._escalate(proc, signal.SIGKILL)

    def done(self) -> bool:
        """The run is over: everything ended, and nothing waits to be started by hand."""
        if self.stopping:
            return all(p.state in TERMINAL or p.state == State.STOPPED for p in self.procs)
        if self.keep_alive or any(p.state == State.STOPPED for p in self.procs):
            return False
        return all(p.state in TERMINAL for p in self.procs)

    # ------------------------------------------------------------------ control by hand

    def stop_process(self, name: str, force: bool = False) -> str:
        """Stop one process by hand: it becomes STOPPED and is not respawned.

        A required process is refused unless ``force``: stopping it is what ends a launch,
        so doing it by accident must not be one keystroke away. Returns what happened.
        """
        proc = self.by_name(name)
        if proc.spec.required and not force:
            raise ControlError(f"{name} is required (its end stops the launch); "
                               "use --force to stop it anyway")
        if self.stopping:
            raise ControlError("the launch is stopping")
        if proc.state == State.BACKOFF:
            self._cancel_timer(proc)
            proc.transition(State.STOPPED, "stopped by hand while waiting to respawn")
        elif proc.state in (State.RUNNING, State.STARTING) and name in self._children:
            self._stop_one(proc, State.STOPPED, "stopped by hand")
        elif proc.state == State.STOPPING:
            proc.after_stop = State.STOPPED
        else:
            return f"{name} is not running ({proc.state})"
        self._changed()
        return f"stopping {name}"

    def start_process(self, name: str) -> str:
        """Start one process that is not running (stopped by hand, ended or failed)."""
        proc = self.by_name(name)
        if self.stopping:
            raise ControlError("the launch is stopping")
        if proc.state == State.STOPPING:
            proc.after_stop = State.STARTING
            return f"{name} is stopping; it starts again once it has"
        if proc.state not in (State.STOPPED, State.EXITED, State.FAILED, State.BACKOFF):
            return f"{name} is already running"
        self._cancel_timer(proc)
        proc.short_runs = 0
        proc.transition(State.STARTING, "started by hand")
        self._spawn(proc)
        return f"started {name}"

    def restart_process(self, name: str) -> str:
        """Stop (SIGINT, escalating) and start again one process; a stopped one just starts."""
        proc = self.by_name(name)
        if self.stopping:
            raise ControlError("the launch is stopping")
        if proc.state in (State.RUNNING, State.STARTING) and name in self._children:
            self._stop_one(proc, State.STARTING, "restarting by hand")
            proc.restarts += 1
            self._changed()
            return f"restarting {name}"
        if proc.state == State.STOPPING:
            proc.after_stop = State.STARTING
            return f"{name} is stopping; it starts again once it has"
        return self.start_process(name)

    def signal_process(self, name: str, signum: int) -> str:
        """Send ``signum`` to one running process's group (what happens next is its exit)."""
        proc = self.by_name(name)
        child = self._children.get(name)
        if child is None:
            return f"{name} is not running ({proc.state})"
        signal_group(child.popen.pid, signum, child.extra)
        return f"sent {signal.Signals(signum).name} to {name}"

    def _stop_one(self, proc: ManagedProcess, after: State, reason: str) -> None:
        pid = self._children[proc.spec.name].popen.pid
        proc.after_stop = after
        self._signal_stop(proc, reason,
                          [d for d in descendants([pid]).get(pid, ()) if _pgid(d) != pid])

    def _signal_stop(self, proc: ManagedProcess, reason: str, extra: list[int]) -> None:
        """SIGINT to a running process's group and ``extra`` (its descendants outside the
        group); SIGTERM after its sigint_timeout, then SIGKILL (``_escalate``)."""
        child = self._children[proc.spec.name]
        child.extra = extra
        proc.transition(State.STOPPING, reason)
        signal_group(child.popen.pid, signal.SIGINT, extra)
        self._set_timer(proc, proc.spec.sigint_timeout,
                        functools.partial(self._escalate, proc, signal.SIGTERM))

    def run(self, install_signals: bool = True,
            before_start: Callable[[], None] | None = None) -> RunResult:
        """Start everything and supervise until the run ends; returns the outcome.

        ``before_start`` runs once the stop signals are ours and before any spawn: where a
        caller announces itself (``orchestra core`` prints its URI there, so a Ctrl-C right
        after it is already an orderly stop).
        """
        restore = self._install_signals() if install_signals else None
        try:
            if restore is not None:   # a stop signal that came before they were ours
                for signum in stop_signals.take():
                    self._stop_signal(signum)
            if before_start is not None:
                before_start()
            with self._watchdog_deferred():
                self.start_all()
            while not self.done():
                with self._watchdog_deferred():   # one write for all the exits of a batch
                    self.loop.run_once()
            # collect what the last exits left in the pipes (bounded: grandchildren may hold them)
            deadline = time.monotonic() + 1.0
            while self._open_pipes and time.monotonic() < deadline:
                self.loop.run_once(limit=max(0.0, deadline - time.monotonic()))
            self._stop_strays()
        finally:
            if restore is not None:
                restore()
            self._close()
        return self._finish()

    # ------------------------------------------------------------------ spawning

    def _spawn(self, proc: ManagedProcess, argv: list[str] | None = None) -> None:
        """Start ``proc`` now, in this thread (``argv``: its command, already vetted)."""
        spec = proc.spec
        if proc.state in (State.BACKOFF, State.STOPPING):
            proc.transition(State.STARTING, "respawn" if proc.state == State.BACKOFF
                            else "restart")
        proc.after_stop = None
        try:
            popen = self._popen(spec, self._command(spec) if argv is None else argv)
        except (OSError, subprocess.SubprocessError) as exc:
            self._spawn_failed(proc, exc)
            return
        self._started(proc, popen)

    def _preexec(self, spec: ProcessSpec) -> Callable[[], None] | None:
        """The Python run in the child between fork and exec, if this spec needs any."""
        return _chain(child_setup(self._pid) if self.pdeathsig == "preexec" else None,
                      rlimit_setup(spec.limits))

    def _command(self, spec: ProcessSpec,
                 vetted: dict[tuple[str, str, str | None], OSError | None] | None = None
                 ) -> list[str]:
        """The argv to exec for ``spec``, or the OSError exec would give (checked here
        because setpriv, not Popen, would meet it); creates the working directory.

        ``vetted`` remembers, for one batch of spawns, what was found for each (program,
        working directory, PATH): a launch of many nodes of few types checks each type once
        (~25 us of file system calls per node, all before the first node is spawned)."""
        argv = list(spec.argv)
        key = (argv[0], spec.cwd, spec.env.get("PATH"))
        if vetted is not None and key in vetted:
            problem = vetted[key]
        else:
            try:
                os.makedirs(spec.cwd, exist_ok=True)
                if self.pdeathsig == "setpriv":
                    check_executable(argv[0], spec.env, spec.cwd)
                problem = None
            except OSError as exc:
                problem = exc
            if vetted is not None:
                vetted[key] = problem
        if problem is not None:
            raise problem
        if self.pdeathsig == "setpriv":
            argv = [*(setpriv_prefix() or ()), *argv]  # checked at __init__
        return argv

    def _popen(self, spec: ProcessSpec, argv: list[str]) -> subprocess.Popen:
        """Fork and exec ``argv``; safe in any thread (touches no supervisor state)."""
        # the child inherits this thread's signal mask through fork and exec
        held = (signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
                if spec.sigint_held else None)
        try:
            return subprocess.Popen(
                argv, cwd=spec.cwd, env={**spec.env, MARK_VARIABLE: self.mark},
                stdin=None,  # inherited, as roslaunch
                stdout=subprocess.PIPE, stderr=subprocess.PIPE, close_fds=True,
                start_new_session=True, preexec_fn=self._preexec(spec))
        finally:
            if held is not None:
                signal.pthread_sigmask(signal.SIG_SETMASK, held)

    def _started(self, proc: ManagedProcess, popen: subprocess.Popen) -> None:
        """Watch a freshly spawned process (exit, output) and mark it RUNNING."""
        spec = proc.spec
        pidfd = _pidfd_open(popen.pid)
        child = _Child(popen, pidfd)
        self._children[spec.name] = child
        if self.watchdog is not None:
            self.watchdog.watch(popen.pid)
        if pidfd is not None:
            self.loop.add_reader(pidfd, lambda: self._on_exit(proc))
        else:
            threading.Thread(target=self._wait_in_thread, args=(proc, popen), daemon=True,
                             name=f"wait {spec.name}").start()
        output = self.outputs[spec.name]
        output.started()
        for stream, pipe in (("out", popen.stdout), ("err", popen.stderr)):
            assert pipe is not None  # both are subprocess.PIPE
            fd = pipe.fileno()
            os.set_blocking(fd, False)
            self._open_pipes += 1
            self.loop.add_reader(fd, functools.partial(self._on_output, fd, stream, pipe, output))
        proc.pid = popen.pid
        proc.started_at = time.monotonic()
        proc.exit_code = None
        if spec.limits.cpu:
            self._limit_cpu(proc, popen.pid)
        proc.transition(State.RUNNING, f"pid {popen.pid}")
        self.screen.message(f"process[{spec.name}]: started with pid [{popen.pid}]")
        self._changed()

    def _spawn_failed(self, proc: ManagedProcess, exc: BaseException) -> None:
        spec = proc.spec
        what = f"cannot start {spec.name} ({' '.join(spec.argv)}): {_oserror_text(exc)}"
        if spec.location:
            what = f"{spec.location}: {what}"
        proc.transition(State.FAILED, what)
        self.screen.message(f"orchestra: error: {what}", err=True)
        if spec.required:
            self.request_stop(f"required process {spec.name} failed to start", exit_code=1)
        self._changed()

    # ------------------------------------------------------------------ events

    def _on_output(self, fd: int, stream: str, pipe, output: NodeOutput,
                   max_reads: int | None = 16) -> None:
        """Forward what is in the pipe; a bounded number of reads so one chatty node cannot
        starve the loop (the selector calls again while data remains)."""
        reads = 0
        while max_reads is None or reads < max_reads:
            reads += 1
            try:
                data = os.read(fd, 65536)
            except BlockingIOError:
                return
            except OSError:
                data = b""
            if not data:
                self.loop.remove_reader(fd)
                pipe.close()
                self._open_pipes -= 1
                output.end(stream)
                return
            output.feed(stream, data)

    def _drain(self, child: _Child, output: NodeOutput) -> None:
        """Read everything the dead child left in its pipes, so no last line is lost."""
        for stream, pipe in (("out", child.popen.stdout), ("err", child.popen.stderr)):
            if pipe is not None and not pipe.closed:
                self._on_output(pipe.fileno(), stream, pipe, output, max_reads=None)

    def _wait_in_thread(self, proc: ManagedProcess, popen: subprocess.Popen) -> None:
        popen.wait()
        self.loop.call_threadsafe(lambda: self._on_exit(proc, popen))

    def _on_exit(self, proc: ManagedProcess, popen: subprocess.Popen | None = None) -> None:
        spec = proc.spec
        child = self._children.get(spec.name)
        if child is None or (popen is not None and child.popen is not popen):
            return    # a late report about an instance already handled
        del self._children[spec.name]
        if child.pidfd is not None:
            self.loop.remove_reader(child.pidfd)
            os.close(child.pidfd)
        code = child.popen.wait()
        # whatever the node left behind in its group (and strays seen at stop) goes with it
        signal_group(child.popen.pid, signal.SIGKILL, child.extra)
        if self.watchdog is not None:
            self.watchdog.forget(child.popen.pid)
        self._drain(child, self.outputs[spec.name])
        self._cancel_timer(proc)
        proc.exit_code = code
        uptime = time.monotonic() - (proc.started_at or time.monotonic())
        if proc.state == State.STOPPING and not self.stopping and proc.after_stop is not None:
            if proc.after_stop == State.STARTING:
                self._spawn(proc)
            else:
                proc.transition(State.STOPPED, f"stopped by hand ({describe_exit(code)})")
                self.screen.message(f"process[{spec.name}]: stopped by hand")
            proc.after_stop = None
            self._changed()
            return
        if proc.state == State.STOPPING or self.stopping:
            proc.transition(State.EXITED, f"stopped ({describe_exit(code)})")
            self._changed()
            return
        described = explain_exit(spec.limits, self.outputs[spec.name].recent,
                                 describe_exit(code))
        if spec.required:
            # a required node that finishes cleanly ends the launch successfully (the
            # "run this job, then stop everything" pattern); any other end is a failure
            if code == 0:
                proc.transition(State.EXITED, "required process finished")
                self.screen.message(f"orchestra: required process [{spec.name}] has finished; "
                                    "shutting down", err=True)
                self.request_stop(f"required process {spec.name} finished", exit_code=0)
                return
            proc.transition(State.EXITED, f"required process died ({described})")
            self.screen.message(
                f"orchestra: required process [{spec.name}] has died ({described}); "
                "shutting down", err=True)
            self.request_stop(f"required process {spec.name} died ({described})", exit_code=1)
            return
        if not spec.respawn:
            proc.transition(State.EXITED, described)
            text = ("has finished cleanly" if code == 0
                    else f"has died [pid {child.popen.pid}, {described}]")
            self.screen.message(f"process[{spec.name}]: {text}{self._log_hint(spec)}",
                                err=code != 0)
            self._changed()
            return
        proc.short_runs = 1 if uptime >= self.policy.stable_after else proc.short_runs + 1
        delay = restart_delay(self.policy, spec.respawn_delay, proc.short_runs)
        if delay is None:
            proc.transition(State.FAILED, f"crash loop: {proc.short_runs} short runs in a row, "
                                          f"last {described}")
            self.screen.message(f"orchestra: {spec.name} keeps dying ({described}); "
                                f"gave up after {proc.restarts} restarts", err=True)
            self._changed()
            return
        proc.transition(State.BACKOFF, f"{described}; respawn in {delay:.3g} s")
        self.screen.message(f"process[{spec.name}]: died ({described}), respawning"
                            + (f" in {delay:.3g} s" if delay > 0 else "")
                            + self._log_hint(spec), err=True)
        proc.restarts += 1
        if delay <= 0:
            self._spawn(proc)
        else:
            self._set_timer(proc, delay, lambda: self._spawn(proc))
        self._changed()

    def _escalate(self, proc: ManagedProcess, sig: int) -> None:
        child = self._children.get(proc.spec.name)
        if child is None or proc.state != State.STOPPING:
            return
        logger.warning("%s did not stop in time: sending %s", proc.spec.name,
                       signal.Signals(sig).name)
        signal_group(child.popen.pid, sig, child.extra)
        if sig == signal.SIGTERM:
            self._set_timer(proc, proc.spec.sigterm_timeout,
                            lambda: self._escalate(proc, signal.SIGKILL))
        else:
            self._cancel_timer(proc)

    # ------------------------------------------------------------------ helpers

    def _limit_cpu(self, proc: ManagedProcess, pid: int) -> None:
        """Put a freshly spawned process under its cpu-limit, or say why it runs without."""
        name = proc.spec.name
        problem = self._cgroup_problem
        if problem is None:
            try:
                group = self._cgroups.get(name) or cpu_cgroup(name, proc.spec.limits.cpu)
                self._cgroups[name] = group
                join_cgroup(group, pid)
                return
            except OSError as exc:
                problem = self._cgroup_problem = f"{exc.strerror or exc}"
        if proc.restarts == 0:
            self.screen.message(f"orchestra: warning: cpu-limit of {name} not enforced: "
                                f"{problem}", err=True)

    def _log_hint(self, spec: ProcessSpec) -> str:
        """roslaunch's pointer to the log files of a node that died."""
        if self.outputs[spec.name].files and self.log_dir and spec.log_name:
            return f"\nlog file: {os.path.join(self.log_dir, spec.log_name)}*.log"
        return ""

    def _watchdog_deferred(self) -> contextlib.AbstractContextManager[None]:
        return (self.watchdog.deferred() if self.watchdog is not None
                else contextlib.nullcontext())

    def _set_timer(self, proc: ManagedProcess, delay: float, callback: Callable[[], None]) -> None:
        self._cancel_timer(proc)
        self._timers[proc.spec.name] = self.loop.call_later(delay, callback)

    def _cancel_timer(self, proc: ManagedProcess) -> None:
        timer = self._timers.pop(proc.spec.name, None)
        if timer is not None:
            timer.cancel()

    def _changed(self) -> None:
        if self.on_change is not None:
            self.on_change()

    def _install_signals(self) -> Callable[[], None] | None:
        """SIGINT/SIGTERM/SIGHUP -> orderly stop; a second one -> SIGKILL what is left."""
        if threading.current_thread() is not threading.main_thread():
            return None
        read_fd, write_fd = os.pipe()
        os.set_blocking(read_fd, False)
        os.set_blocking(write_fd, False)
        old_wakeup = signal.set_wakeup_fd(write_fd, warn_on_full_buffer=False)
        old_handlers = {sig: signal.signal(sig, lambda *_: None) for sig in _STOP_SIGNALS}

        def on_signal() -> None:
            try:
                data = os.read(read_fd, 64)
            except BlockingIOError:
                return
            for signum in data:
                self._stop_signal(signum)

        self.loop.add_reader(read_fd, on_signal)

        def restore() -> None:
            signal.set_wakeup_fd(old_wakeup)
            for sig, handler in old_handlers.items():
                signal.signal(sig, handler)
            self.loop.remove_reader(read_fd)
            os.close(read_fd)
            os.close(write_fd)

        return restore

    def _stop_signal(self, signum: int) -> None:
        """The first stop signal: orderly stop; any further one: SIGKILL what is left."""
        if signum not in _STOP_SIGNALS:
            return
        self._signal_count += 1
        name = stop_signals.name(signum)
        if self._signal_count == 1:
            self.screen.message(f"orchestra: {name} received, stopping all nodes", err=True)
            self.request_stop(f"{name} received")
        else:
            self.screen.message(f"orchestra: {name} again, killing all nodes", err=True)
            self.kill_all()

    def _stop_strays(self) -> None:
        """Stop what nodes left running outside their process groups (setsid, daemons).

        Every node is gone by now, so anything still carrying this run's mark escaped its
        node's group: it gets SIGTERM, then SIGKILL after ``stray_timeout``. roslaunch leaves
        such processes running forever.
        """
        pids = marked_pids(self.mark)
        if not pids:
            return
        import psutil  # (only now: not among what a launch imports before its nodes start)

        strays = []
        for pid in pids:
            try:
                strays.append(psutil.Process(pid))
            except psutil.NoSuchProcess:
                pass
        if not strays:
            return
        names = []
        for ps in strays:
            try:
                names.append(f"{ps.pid} ({ps.name()})")
            except psutil.Error:
                names.append(str(ps.pid))
        self.screen.message(f"orchestra: stopping {len(strays)} process(es) that nodes left "
                            f"running outside their process groups: {', '.join(names)}",
                            err=True)
        for ps in strays:
            try:
                ps.terminate()
            except psutil.Error:
                pass
        _, alive = psutil.wait_procs(strays, timeout=self.stray_timeout)
        for ps in alive:
            try:
                ps.kill()
            except psutil.Error:
                pass
        psutil.wait_procs(alive, timeout=self.stray_timeout)

    def _close(self) -> None:
        for output in self.outputs.values():
            output.close()
        for group in self._cgroups.values():
            remove_cgroup(group)
        for child in self._children.values():  # only after an internal error
            signal_group(child.popen.pid, signal.SIGKILL, child.extra)
            child.popen.wait()
            if child.pidfd is not None:
                os.close(child.pidfd)
        self._children.clear()
        self._spawner.close()     # only now: a child dies with the thread that spawned it
        self.loop.close()

    def _finish(self) -> RunResult:
        failed = [p.spec.name for p in self.procs if p.state == State.FAILED]
        result = self.result or RunResult(0, "all processes ended")
        result.failed = failed
        if failed and result.exit_code == 0:
            result.exit_code = 1
            result.reason = result.reason + "; failed: " + ", ".join(failed)
        return result


class ControlError(Exception):
    """A control request that cannot be done (the message says why); the run goes on."""


def _chain(*steps: Callable[[], None] | None) -> Callable[[], None] | None:
    """One ``preexec_fn`` running the given steps in order (None when there are none)."""
    todo = [step for step in steps if step is not None]
    if not todo:
        return None

    def run() -> None:
        for step in todo:
            step()

    return run


def _pidfd_open(pid: int) -> int | None:
    """A pidfd for ``pid``, or None where the kernel/Python has none."""
    if not _HAS_PIDFD:
        return None
    try:
        return os.pidfd_open(pid)
    except OSError as exc:
        if exc.errno in (errno.ENOSYS, errno.EPERM, errno.EINVAL):
            return None
        raise


_HAS_PIDFD = hasattr(os, "pidfd_open") and os.environ.get("ORCHESTRA_NO_PIDFD") != "1"


def _pgid(pid: int) -> int | None:
    try:
        return os.getpgid(pid)
    except OSError:
        return None


def _oserror_text(exc: BaseException) -> str:
    if isinstance(exc, OSError) and exc.strerror:
        text = exc.strerror
        if exc.errno == 8:
            text += " (a script needs a '#!' line)"
        return text
    return str(exc)
