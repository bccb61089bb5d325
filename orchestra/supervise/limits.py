"""rosmon's resource attributes put into effect by the kernel: memory, CPU, core dumps.

rosmon only watches ``memory-limit``/``cpu-limit`` and highlights a node past them; orchestra
asks the kernel to enforce them, so a leaking node fails on its own instead of taking the
machine with it:

- ``memory-limit``: RLIMIT_AS, set in the child before exec. An allocation past it fails
  (Python raises MemoryError, C++ throws std::bad_alloc), so the node dies and the supervisor
  explains the exit from its last output lines (``explain_exit``).
- ``cpu-limit`` (a fraction of one core): a cgroup v2 ``cpu.max`` when this process's cgroup
  can hold child groups with the cpu controller; otherwise it is reported as not enforced
  (``cgroup_unavailable``) and the node runs unlimited.
- ``enable-coredumps``: RLIMIT_CORE lifted to the hard limit for that node only.
"""
from __future__ import annotations

import logging
import os
import resource
from collections.abc import Callable, Iterable

from orchestra.supervise.process import Limits

logger = logging.getLogger(__name__)

CPU_PERIOD_US = 100_000
_ALLOCATION_FAILURES = (b"MemoryError", b"std::bad_alloc", b"Cannot allocate memory",
                        b"out of memory")


def rlimit_setup(limits: Limits) -> Callable[[], None] | None:
    """A ``preexec_fn`` part applying the rlimits of ``limits`` (None when it has none)."""
    if not (limits.memory or limits.coredumps):
        return None

    def setup() -> None:
        if limits.memory:
            resource.setrlimit(resource.RLIMIT_AS, (limits.memory, limits.memory))
        if limits.coredumps:
            _, hard = resource.getrlimit(resource.RLIMIT_CORE)
            resource.setrlimit(resource.RLIMIT_CORE, (hard, hard))

    return setup


def explain_exit(limits: Limits, recent: Iterable[bytes], described: str) -> str:
    """Why a node under ``memory-limit`` died, when its last lines show a failed allocation."""
    if not limits.memory:
        return described
    if any(marker in line for line in recent for marker in _ALLOCATION_FAILURES):
        return (f"{described}: an allocation failed past its memory-limit of "
                f"{format_bytes(limits.memory)}")
    return described


def format_bytes(size: int) -> str:
    for unit in ("B", "KiB", "MiB", "GiB"):
        if size < 1024 or unit == "GiB":
            return f"{size:g} {unit}" if unit == "B" else f"{size:.3g} {unit}"
        size /= 1024  # type: ignore[assignment]
    return f"{size} B"


def _own_cgroup_dir() -> str | None:
    """This process's cgroup v2 directory, when the unified hierarchy is mounted."""
    try:
        with open("/proc/self/cgroup", encoding="utf-8") as fh:
            path = next((line.strip()[3:] for line in fh if line.startswith("0::")), None)
        with open("/proc/self/mountinfo", encoding="utf-8") as fh:
            mounts = [line.split() for line in fh]
    except OSError:
        return None
    roots = [fields[4] for fields in mounts if "cgroup2" in fields[fields.index("-") + 1:]]
    if path is None or not roots:
        return None
    return os.path.join(roots[0], path.lstrip("/"))


def cgroup_unavailable() -> str | None:
    """Why ``cpu-limit`` cannot be enforced here, or None when a cgroup v2 can hold it."""
    base = _own_cgroup_dir()
    if base is None:
        return "no cgroup v2 hierarchy is mounted"
    try:
        with open(os.path.join(base, "cgroup.controllers"), encoding="utf-8") as fh:
            controllers = fh.read().split()
    except OSError as exc:
        return f"cannot read {base}/cgroup.controllers: {exc.strerror}"
    if "cpu" not in controllers:
        return f"the cpu controller is not delegated to {base}"
    if not os.access(base, os.W_OK):
        return f"{base} is not writable by this user"
    return None


def cpu_cgroup(name: str, fraction: float) -> str:
    """Create the cgroup holding one node at ``fraction`` of a core; returns its directory.

    Raises OSError when the kernel refuses (the caller reports and runs the node unlimited).
    """
    base = _own_cgroup_dir()
    if base is None:
        raise OSError("no cgroup v2 hierarchy is mounted")
    group = os.path.join(base, f"orchestra-{os.getpid()}-{name.strip('/').replace('/', '-')}")
    os.makedirs(group, exist_ok=True)
    with open(os.path.join(base, "cgroup.subtree_control"), "w", encoding="utf-8") as fh:
        fh.write("+cpu")
    with open(os.path.join(group, "cpu.max"), "w", encoding="utf-8") as fh:
        fh.write(f"{max(1000, int(fraction * CPU_PERIOD_US))} {CPU_PERIOD_US}")
    return group


def join_cgroup(group: str, pid: int) -> None:
    with open(os.path.join(group, "cgroup.procs"), "w", encoding="utf-8") as fh:
        fh.write(str(pid))


def remove_cgroup(group: str) -> None:
    try:
        os.rmdir(group)
    except OSError as exc:
        logger.debug("cannot remove %s: %s", group, exc)
