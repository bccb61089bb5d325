"""One supervised process: what to run (ProcessSpec), its state machine and its restart rule.

The states are supervisord's, because they make a node's situation explicit where roslaunch
only knows "alive or not":

    STARTING -> RUNNING -> (EXITED | BACKOFF -> STARTING ... | FAILED)
                RUNNING -> STOPPING -> EXITED
    by hand:    RUNNING -> STOPPING -> STOPPED -> STARTING ...   (stop, then start)
                RUNNING -> STOPPING -> STARTING -> RUNNING       (restart)
                EXITED | FAILED | BACKOFF -> STARTING              (start)

STOPPED is its own state because a node stopped by hand differs from one that ended: it is
not respawned, a required one does not end the launch, and the launch keeps running for it
to be started again (rosmon's and supervisorctl's model).

This module holds data and pure rules only; the Supervisor does the side effects and calls
``ManagedProcess.transition`` so that every change is checked and logged in one place.
"""
from __future__ import annotations

import enum
import logging
import time
from collections.abc import Mapping
from dataclasses import dataclass, field

logger = logging.getLogger(__name__)


class State(str, enum.Enum):
    STARTING = "STARTING"    # spawn requested, exec not confirmed yet
    RUNNING = "RUNNING"      # exec succeeded; the process is alive
    BACKOFF = "BACKOFF"      # died, waiting for its respawn delay
    STOPPING = "STOPPING"    # we asked it to stop (SIGINT, then SIGTERM, then SIGKILL)
    EXITED = "EXITED"        # ended and will not be restarted (stopped, or ended by itself)
    STOPPED = "STOPPED"      # stopped by hand; waits to be started by hand
    FAILED = "FAILED"        # could not be spawned, or crash-looped past the limit

    def __str__(self) -> str:
        return self.value


TERMINAL = frozenset({State.EXITED, State.FAILED})

_ALLOWED: dict[State, frozenset[State]] = {
    State.STARTING: frozenset({State.RUNNING, State.FAILED, State.EXITED}),
    State.RUNNING: frozenset({State.STOPPING, State.EXITED, State.BACKOFF, State.FAILED}),
    State.BACKOFF: frozenset({State.STARTING, State.EXITED, State.STOPPED}),
    State.STOPPING: frozenset({State.EXITED, State.STOPPED, State.STARTING}),
    State.EXITED: frozenset({State.STARTING}),
    State.FAILED: frozenset({State.STARTING}),
    State.STOPPED: frozenset({State.STARTING, State.EXITED}),
}


class OutputMode(str, enum.Enum):
    SCREEN = "screen"   # stdout and stderr on the console, prefixed with the node name
    LOG = "log"         # stdout to the log file; stderr to the log file AND the console
    BOTH = "both"       # both streams to the log files and the console


@dataclass(frozen=True)
class Limits:
    """rosmon's per-node resource attributes, as the kernel is asked to enforce them.

    ``memory`` is bytes of address space (RLIMIT_AS; 0 = none), ``cpu`` a fraction of one
    core (cgroup v2 ``cpu.max``; 0 = none), ``coredumps`` lifts RLIMIT_CORE to unlimited.
    """

    memory: int = 0
    cpu: float = 0.0
    coredumps: bool = False

    def __bool__(self) -> bool:
        return bool(self.memory or self.cpu or self.coredumps)


@dataclass(frozen=True)
class ProcessSpec:
    """Everything needed to (re)start one process; built once from the plan, never mutated.

    ``env`` is the complete environment (not additions). ``log_name`` is the base of the log
    file names (``robot1-listener-3``), None when nothing is logged.
    """

    name: str
    argv: tuple[str, ...]
    env: Mapping[str, str]
    cwd: str
    respawn: bool = False
    respawn_delay: float = 0.0
    required: bool = False
    output: OutputMode = OutputMode.LOG
    log_name: str | None = None
    sigint_timeout: float = 15.0
    sigterm_timeout: float = 2.0
    location: str | None = None
    limits: Limits = field(default_factory=Limits)
    # started with SIGINT blocked: the program unblocks it once its handlers are installed
    # (orchestra's own core nodes do), so a stop that comes while its interpreter is still
    # starting is delivered then and ends it cleanly, not mid-import with a traceback
    sigint_held: bool = False


@dataclass(frozen=True)
class RestartPolicy:
    """How respawning backs off, so that a crash-looping node cannot eat the machine.

    The first restart after a stable run waits only the node's ``respawn_delay`` (roslaunch
    behaviour, and what keeps crash->respawn latency low). Each further run shorter than
    ``stable_after`` seconds doubles the wait from ``backoff_initial`` up to ``backoff_max``;
    after ``crash_limit`` such short runs in a row the process is FAILED (0 = never give up).
    """

    backoff_initial: float = 0.5
    backoff_factor: float = 2.0
    backoff_max: float = 30.0
    stable_after: float = 10.0
    crash_limit: int = 10


def restart_delay(policy: RestartPolicy, respawn_delay: float, short_runs: int) -> float | None:
    """Seconds to wait before the next start after ``short_runs`` short runs in a row.

    None means give up. ``short_runs`` counts the run that just ended (1 = first failure).
    """
    if policy.crash_limit and short_runs >= policy.crash_limit:
        return None
    if short_runs <= 1:
        return max(0.0, respawn_delay)
    backoff = policy.backoff_initial * policy.backoff_factor ** (short_runs - 2)
    return max(respawn_delay, min(policy.backoff_max, backoff))


@dataclass
class ManagedProcess:
    """The live side of a ProcessSpec: state, current pid, counters."""

    spec: ProcessSpec
    state: State = State.STARTING
    pid: int | None = None
    restarts: int = 0
    short_runs: int = 0
    started_at: float | None = None      # time.monotonic() of the current/last start
    exit_code: int | None = None
    reason: str = ""                     # why it is FAILED / EXITED, for status and errors
    start_index: int = 0                 # order of first start (stop goes in reverse)
    after_stop: State | None = None      # by hand: STOPPED (stop) or STARTING (restart)
    history: list[tuple[float, State]] = field(default_factory=list)

    def transition(self, new: State, reason: str = "") -> None:
        """Move to ``new``; an impossible move is a bug in the supervisor, so it raises."""
        if new == self.state and new == State.STARTING:
            return
        if new not in _ALLOWED[self.state]:
            raise RuntimeError(f"{self.spec.name}: illegal transition {self.state} -> {new}")
        logger.info("%s: %s -> %s%s", self.spec.name, self.state, new,
                    f" ({reason})" if reason else "")
        self.state = new
        if reason:
            self.reason = reason
        self.history.append((time.monotonic(), new))

    @property
    def uptime(self) -> float:
        if self.state in (State.RUNNING, State.STOPPING) and self.started_at is not None:
            return time.monotonic() - self.started_at
        return 0.0


def describe_exit(code: int | None) -> str:
    """``exit code 3`` / ``killed by SIGKILL`` from a Popen returncode."""
    import signal

    if code is None:
        return "no exit code"
    if code < 0:
        try:
            return f"killed by {signal.Signals(-code).name}"
        except ValueError:
            return f"killed by signal {-code}"
    return f"exit code {code}"
