"""Making sure no node outlives orchestra: process groups, parent-death signal, watchdog.

Each node runs in its own session (like roslaunch), so a Ctrl-C on the terminal reaches only
orchestra, which then stops nodes in order. The price roslaunch pays for that is orphans when
it is SIGKILLed; orchestra closes the gap twice:

- every child asks the kernel for SIGKILL when orchestra dies (``PR_SET_PDEATHSIG``, set in
  the child between fork and exec);
- a tiny forked watchdog process holds the read end of a pipe and learns each node's process
  group; when the pipe closes without a goodbye (orchestra died), it SIGKILLs every group, so
  grandchildren a node forked die too;
- every node's environment carries a run mark (``ORCHESTRA_RUN_MARK``), which whatever it
  starts inherits. A grandchild that left its node's process group and session (``setsid``,
  a double-forked daemon) is no longer anyone's descendant once its node is gone, but its
  ``/proc/PID/environ`` still names the run: the watchdog (orchestra killed) and the end of a
  normal run (nodes that died leaving such strays behind) find those processes by the mark.

Setting the parent-death signal from Python (``preexec_fn``) forces a full fork of the
interpreter and costs ~7 ms per spawn; util-linux's ``setpriv --pdeathsig`` does the same
from a tiny exec'd program for ~1 ms, so it is used when present. Because ``setpriv`` execs
with ``execvp`` (which would run a script without ``#!`` under /bin/sh, where Python's Popen
reports "Exec format error"), ``check_executable`` vets the target first.
"""
from __future__ import annotations

import contextlib
import errno
import functools
import logging
import os
import shutil
import signal
import subprocess
import time
import warnings
from collections.abc import Callable, Iterable, Iterator, Mapping

logger = logging.getLogger(__name__)

PR_SET_PDEATHSIG = 1
MARK_VARIABLE = "ORCHESTRA_RUN_MARK"
#: how long (s) the watchdog of a killed orchestra looks for marked processes, and how often
SPAWN_GRACE = 1.0
SPAWN_SCAN = 0.05

# psutil and ctypes are imported where they are used (the stray scan without /proc, the
# preexec fallback): a launch imports this module before its first node starts


@functools.cache
def _prctl() -> Callable[..., int] | None:
    import ctypes

    try:
        return ctypes.CDLL(None, use_errno=True).prctl
    except (OSError, AttributeError):  # not Linux: the watchdog alone covers it
        return None


def child_setup(parent_pid: int) -> Callable[[], None]:
    """A ``preexec_fn`` that ties the child's life to ``parent_pid`` (runs in the child)."""
    prctl = _prctl()   # looked up here, in the parent: the child only calls it

    def setup() -> None:
        if prctl is not None:
            prctl(PR_SET_PDEATHSIG, signal.SIGKILL, 0, 0, 0)
        if os.getppid() != parent_pid:   # the parent died before prctl took effect
            os._exit(127)

    return setup


@functools.cache
def setpriv_prefix() -> tuple[str, ...] | None:
    """``setpriv --pdeathsig KILL --`` when this machine's setpriv supports it, else None."""
    path = shutil.which("setpriv")
    if path is None:
        return None
    try:
        probe = subprocess.run([path, "--pdeathsig", "KILL", "--", "true"],
                               stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, timeout=5)
    except (OSError, subprocess.SubprocessError):
        return None
    return (path, "--pdeathsig", "KILL", "--") if probe.returncode == 0 else None


def check_executable(program: str, env: Mapping[str, str], cwd: str) -> None:
    """Raise the OSError exec would raise for ``program`` (not found, not executable, no #!)."""
    path: str | None
    if os.sep in program:
        path = program if os.path.isabs(program) else os.path.join(cwd, program)
    else:
        path = shutil.which(program, path=env.get("PATH", os.defpath))
        if path is None:
            raise FileNotFoundError(errno.ENOENT, os.strerror(errno.ENOENT), program)
    if not os.path.exists(path):
        raise FileNotFoundError(errno.ENOENT, os.strerror(errno.ENOENT), program)
    if os.path.isdir(path) or not os.access(path, os.X_OK):
        raise PermissionError(errno.EACCES, os.strerror(errno.EACCES), program)
    with open(path, "rb") as fh:
        head = fh.read(4)
    if not (head.startswith(b"#!") or head == b"\x7fELF"):
        raise OSError(errno.ENOEXEC, os.strerror(errno.ENOEXEC), program)


def signal_group(pgid: int, sig: int, extra: Iterable[int] = ()) -> None:
    """Send ``sig`` to a process group and to stray descendants that left it; ignore the gone."""
    try:
        os.killpg(pgid, sig)
    except (ProcessLookupError, PermissionError):
        pass
    for pid in extra:
        try:
            os.kill(pid, sig)
        except (ProcessLookupError, PermissionError):
            pass


def _children_table() -> dict[int, list[int]]:
    """Parent pid -> its children's pids, for every live process.

    Read from ``/proc/PID/stat`` directly where there is one: the stop of a launch waits
    for this before signalling its nodes, and psutil's per-process objects made it
    ~10x slower (tens of ms on a loaded machine with a few hundred processes).
    """
    children: dict[int, list[int]] = {}
    try:
        entries = os.listdir("/proc")
    except OSError:
        entries = None
    if entries is None or not os.path.exists("/proc/self/stat"):
        import psutil

        for proc in psutil.process_iter(["ppid"]):
            ppid = proc.info.get("ppid")
            if ppid is not None:
                children.setdefault(ppid, []).append(proc.pid)
        return children
    for entry in entries:
        if not entry.isdigit():
            continue
        try:
            with open(f"/proc/{entry}/stat", "rb") as fh:
                stat = fh.read()
        except OSError:
            continue          # gone meanwhile
        # "pid (comm) state ppid ...": comm may hold spaces and parentheses
        fields = stat[stat.rfind(b")") + 2:].split(b" ", 2)
        if len(fields) >= 2:
            children.setdefault(int(fields[1]), []).append(int(entry))
    return children


def descendants(roots: Iterable[int]) -> dict[int, list[int]]:
    """For each root pid, all its live descendants (one pass over the process table)."""
    children = _children_table()
    result: dict[int, list[int]] = {}
    for root in roots:
        found: list[int] = []
        stack = list(children.get(root, ()))
        while stack:
            pid = stack.pop()
            found.append(pid)
            stack.extend(children.get(pid, ()))
        result[root] = found
    return result


def new_mark() -> str:
    """A value for MARK_VARIABLE that no other run on this machine uses."""
    return f"{os.getpid()}-{os.urandom(8).hex()}"   # (secrets' source, without its import)


def marked_pids(mark: str, exclude: Iterable[int] = ()) -> list[int]:
    """Live processes whose initial environment carries ``MARK_VARIABLE=mark``.

    Plain reads of ``/proc`` (no psutil, no threads): the watchdog calls this in a forked
    child. Processes of other users, and those that vanish mid-scan, are skipped.
    """
    needle = f"{MARK_VARIABLE}={mark}".encode()
    skip = set(exclude) | {os.getpid()}
    found: list[int] = []
    try:
        entries = os.listdir("/proc")
    except OSError:
        return found
    for entry in entries:
        if not entry.isdigit() or int(entry) in skip:
            continue
        try:
            with open(f"/proc/{entry}/environ", "rb") as fh:
                environ = fh.read()
        except OSError:
            continue
        if needle in environ.split(b"\0"):
            found.append(int(entry))
    return found


class Watchdog:
    """A forked helper that SIGKILLs every registered process group if orchestra dies.

    Fork it before starting threads or opening server sockets: the child closes every other
    descriptor and touches nothing but the pipe and ``kill``.
    """

    def __init__(self) -> None:
        #: the value of MARK_VARIABLE in every node's environment (unique to this run)
        self.mark = new_mark()
        read_fd, write_fd = os.pipe()
        # the stop signals stay blocked across the fork until the child ignores them: a
        # Ctrl-C at that instant must not raise KeyboardInterrupt in the child
        stops = {signal.SIGINT, signal.SIGTERM, signal.SIGHUP}
        held = signal.pthread_sigmask(signal.SIG_BLOCK, stops)
        try:
            with warnings.catch_warnings():
                # Python >= 3.12 warns about fork() with threads running (an embedded master
                # in tests); the child only makes raw system calls, which is fork-safe
                warnings.simplefilter("ignore", DeprecationWarning)
                pid = os.fork()
            if pid == 0:  # child
                try:
                    os.close(write_fd)
                    _watchdog_main(read_fd, self.mark, held)
                finally:
                    os._exit(0)
        finally:
            signal.pthread_sigmask(signal.SIG_SETMASK, held)
        os.close(read_fd)
        self.pid = pid
        self._pending: list[str] = []
        self._deferring = False
        self._fd: int | None = write_fd
        os.set_inheritable(write_fd, False)

    def _send(self, text: str) -> None:
        self._pending.append(text)
        if not self._deferring:
            self.flush()

    def flush(self) -> None:
        """Write what ``deferred()`` held back."""
        text, self._pending = "".join(self._pending), []
        if self._fd is None or not text:
            return
        try:
            os.write(self._fd, text.encode())
        except OSError as exc:
            logger.warning("watchdog unreachable: %s", exc)

    @contextlib.contextmanager
    def deferred(self) -> Iterator[None]:
        """Send the changes made inside in one write at the end: each write wakes the
        watchdog process, and starting or stopping 100 nodes woke it 100 times. (Until
        then it does not know the newest groups; the run mark and the parent-death signal
        still cover those.)"""
        self._deferring = True
        try:
            yield
        finally:
            self._deferring = False
            self.flush()

    def watch(self, pgid: int) -> None:
        self._send(f"+{pgid}\n")

    def forget(self, pgid: int) -> None:
        self._send(f"-{pgid}\n")

    def close(self) -> None:
        """Clean exit: tell the watchdog there is nothing to kill, and reap it."""
        if self._fd is None:
            return
        self._deferring = False
        self._send("bye\n")
        os.close(self._fd)
        self._fd = None
        try:
            os.waitpid(self.pid, 0)
        except ChildProcessError:
            pass


def _watchdog_main(read_fd: int, mark: str, mask: Iterable[int]) -> None:
    for sig in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP, signal.SIGPIPE):
        signal.signal(sig, signal.SIG_IGN)
    signal.pthread_sigmask(signal.SIG_SETMASK, mask)
    try:
        os.setsid()   # a kill aimed at orchestra's process group must not take us along
    except OSError:
        pass
    os.closerange(3, read_fd)
    os.closerange(read_fd + 1, 65536)
    groups: set[int] = set()
    buf = b""
    clean = False
    while True:
        try:
            chunk = os.read(read_fd, 4096)
        except InterruptedError:
            continue
        except OSError:
            break
        if not chunk:
            break
        buf += chunk
        *lines, buf = buf.split(b"\n")
        for line in lines:
            if line == b"bye":
                clean = True
            elif line[:1] == b"+":
                groups.add(int(line[1:]))
            elif line[:1] == b"-":
                groups.discard(int(line[1:]))
    if clean:
        return
    for pgid in groups:
        try:
            os.killpg(pgid, signal.SIGKILL)
        except OSError as exc:
            if exc.errno not in (errno.ESRCH, errno.EPERM):
                raise
    # strays that left their node's group (setsid): found by the mark they inherited. The
    # scan goes on for SPAWN_GRACE: a node orchestra was spawning when it died carries the
    # mark only once it has exec'd, and a child forked before its parent-death signal was
    # set (setpriv sets it after the fork) outlives orchestra; on a busy machine that exec
    # came up to ~0.3 s after the fork (a rosout spawned as `orchestra core` was killed)
    end = time.monotonic() + SPAWN_GRACE
    while True:
        for pid in marked_pids(mark):
            try:
                os.kill(pid, signal.SIGKILL)
            except OSError:
                pass
        if time.monotonic() >= end:
            return
        time.sleep(SPAWN_SCAN)
