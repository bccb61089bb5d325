"""What a running launch reports about its nodes: the snapshot, the table, the status socket.

A running ``orchestra launch`` serves its snapshot as one JSON document on a Unix socket in
a per-user runtime directory (``$XDG_RUNTIME_DIR/orchestra`` or ``/tmp/orchestra-<uid>``),
named after its pid. ``orchestra status`` connects to every socket there, so it needs
neither a master nor a port, and one user cannot read another's launches.
"""
from __future__ import annotations

import json
import os
import socket
import stat
import xmlrpc.client
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from orchestra.rpc import call, unpack_reply
from orchestra.supervise.loop import EventLoop, Timer
from orchestra.supervise.process import ManagedProcess, State

if TYPE_CHECKING:
    import psutil

SNAPSHOT_VERSION = 1
MAX_SOCKET_DIR = 90


def runtime_dir(environ: dict[str, str] | None = None) -> str:
    """The per-user directory holding the status sockets (created 0700 when missing)."""
    env = os.environ if environ is None else environ
    base = env.get("XDG_RUNTIME_DIR")
    path = os.path.join("/tmp", f"orchestra-{os.getuid()}")
    # a Unix socket path must fit in 108 bytes ("/<pid>.sock" included)
    if base and os.path.isdir(base) and os.access(base, os.W_OK) \
            and len(os.path.join(base, "orchestra")) <= MAX_SOCKET_DIR:
        path = os.path.join(base, "orchestra")
    os.makedirs(path, mode=0o700, exist_ok=True)
    return path


class ProcessStats:
    """CPU% and RSS per pid, keeping psutil handles so CPU% is measured between two calls."""

    def __init__(self) -> None:
        self._handles: dict[int, psutil.Process] = {}

    def sample(self, pid: int | None) -> tuple[float | None, int | None]:
        if pid is None:
            return None, None
        import psutil  # at the first status request, not before a launch's nodes start

        handle = self._handles.get(pid)
        try:
            if handle is None:
                handle = self._handles[pid] = psutil.Process(pid)
            with handle.oneshot():
                return handle.cpu_percent(None), handle.memory_info().rss
        except (psutil.NoSuchProcess, psutil.AccessDenied, psutil.ZombieProcess):
            self._handles.pop(pid, None)
            return None, None

    def forget_except(self, pids: set[int]) -> None:
        for pid in list(self._handles):
            if pid not in pids:
                del self._handles[pid]


def node_status(proc: ManagedProcess, stats: ProcessStats) -> dict[str, Any]:
    live = proc.state in (State.RUNNING, State.STOPPING)
    cpu, rss = stats.sample(proc.pid) if live else (None, None)
    return {
        "name": proc.spec.name,
        "state": proc.state.value,
        "pid": proc.pid if live else None,
        "restarts": proc.restarts,
        "uptime": round(proc.uptime, 3),
        "cpu_percent": cpu,
        "rss": rss,
        "exit_code": proc.exit_code,
        "required": proc.spec.required,
        "respawn": proc.spec.respawn,
        "reason": proc.reason,
    }


def snapshot(procs: list[ManagedProcess], stats: ProcessStats, info: dict[str, Any]) -> dict[str, Any]:
    """The JSON document ``orchestra status --json`` prints for one launch."""
    nodes = [node_status(p, stats) for p in procs]
    stats.forget_except({n["pid"] for n in nodes if n["pid"] is not None})
    return {"version": SNAPSHOT_VERSION, "pid": os.getpid(), **info, "nodes": nodes}


def format_duration(seconds: float) -> str:
    seconds = int(seconds)
    if seconds < 60:
        return f"{seconds}s"
    if seconds < 3600:
        return f"{seconds // 60}m{seconds % 60:02d}s"
    return f"{seconds // 3600}h{seconds // 60 % 60:02d}m"


def format_size(rss: int | None) -> str:
    if rss is None:
        return "-"
    size: float = rss
    for unit in ("B", "K", "M", "G"):
        if size < 1024 or unit == "G":
            return f"{size:.0f}{unit}" if unit == "B" else f"{size:.1f}{unit}"
        size /= 1024
    return "-"


def table_lines(nodes: list[dict[str, Any]]) -> list[str]:
    """One compact line per node: name, state, pid, restarts, uptime, CPU%, RSS, and why a
    node is not running (stopped by hand, exit code, crash loop) when any is not."""
    width = max([len("NODE")] + [len(n["name"]) for n in nodes])
    reasons = [n.get("reason") or "" if n["state"] != State.RUNNING.value else ""
               for n in nodes]
    tail = "  REASON" if any(reasons) else ""
    lines = [f"{'NODE':<{width}}  {'STATE':<8} {'PID':>7} {'RESTARTS':>8} {'UPTIME':>8} "
             f"{'CPU%':>6} {'RSS':>7}{tail}"]
    for n, reason in zip(nodes, reasons, strict=True):
        cpu = "-" if n["cpu_percent"] is None else f"{n['cpu_percent']:.1f}"
        pid = "-" if n["pid"] is None else str(n["pid"])
        uptime = format_duration(n["uptime"]) if n["pid"] is not None else "-"
        why = f"  {reason}" if tail and reason else ""
        lines.append(f"{n['name']:<{width}}  {n['state']:<8} {pid:>7} {n['restarts']:>8} "
                     f"{uptime:>8} {cpu:>6} {format_size(n['rss']):>7}{why}")
    return lines


def summary_line(nodes: list[dict[str, Any]]) -> str:
    counts: dict[str, int] = {}
    for n in nodes:
        counts[n["state"]] = counts.get(n["state"], 0) + 1
    parts = [f"{counts[s.value]} {s.value}" for s in State if s.value in counts]
    return f"{len(nodes)} nodes: " + ", ".join(parts)


def footer_lines(nodes: list[dict[str, Any]], max_lines: int) -> list[str]:
    """The live view: the full table when it fits, else a summary plus the unhealthy nodes."""
    if len(nodes) + 1 <= max_lines:
        return table_lines(nodes)
    unhealthy = [n for n in nodes if n["state"] != State.RUNNING.value]
    shown = table_lines(unhealthy[:max(0, max_lines - 2)]) if unhealthy else []
    return [summary_line(nodes)] + shown


class StatusServer:
    """The launch's user-only control socket, served from the supervisor's loop (no thread).

    A client sends one JSON document on one line and reads one JSON line back:
    ``{"op": "status"}`` answers the snapshot; any other op goes to ``control`` (see
    control.py). Connections are read without blocking, so two clients at once, a client
    that dies mid-request, or garbage on the socket cost the launch nothing: each is
    answered or dropped on its own, within ``timeout`` seconds.
    """

    MAX_REQUEST = 1 << 20

    def __init__(self, loop: EventLoop, make_snapshot: Callable[[], dict[str, Any]],
                 path: str | None = None,
                 control: Callable[[dict[str, Any]], dict[str, Any]] | None = None,
                 timeout: float = 2.0):
        self.path = path or os.path.join(runtime_dir(), f"{os.getpid()}.sock")
        if os.path.exists(self.path):
            os.unlink(self.path)
        self._sock = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        self._sock.bind(self.path)
        os.chmod(self.path, stat.S_IRUSR | stat.S_IWUSR)
        self._sock.listen(16)
        self._sock.setblocking(False)
        self._loop = loop
        self._make = make_snapshot
        self._control = control
        self._timeout = timeout
        self._conns: dict[int, tuple[socket.socket, bytearray, Any]] = {}
        loop.add_reader(self._sock.fileno(), self._accept)

    def _accept(self) -> None:
        try:
            conn, _ = self._sock.accept()
        except OSError:
            return
        conn.setblocking(False)
        fd = conn.fileno()
        timer = self._loop.call_later(self._timeout, lambda: self._drop(fd))
        self._conns[fd] = (conn, bytearray(), timer)
        self._loop.add_reader(fd, lambda: self._read(fd))

    def _read(self, fd: int) -> None:
        conn, buf, _ = self._conns[fd]
        try:
            data = conn.recv(65536)
        except BlockingIOError:
            return
        except OSError:
            data = b""
        if not data:                          # the client went away mid-request
            self._drop(fd)
            return
        buf += data
        if b"\n" not in buf and len(buf) <= self.MAX_REQUEST:
            return
        line = bytes(buf.split(b"\n", 1)[0])
        answer = self._answer(line)
        try:
            conn.setblocking(True)
            conn.settimeout(1.0)
            conn.sendall(json.dumps(answer).encode() + b"\n")
        except OSError:
            pass
        self._drop(fd)

    def _answer(self, line: bytes) -> dict[str, Any]:
        try:
            request = json.loads(line)
        except ValueError:
            return {"ok": False, "error": "not a JSON request"}
        if not isinstance(request, dict):
            return {"ok": False, "error": "a request is a JSON object with an 'op'"}
        if request.get("op") == "status":
            return self._make()
        if self._control is None:
            return {"ok": False, "error": "this launch takes no control requests"}
        return self._control(request)

    def _drop(self, fd: int) -> None:
        entry = self._conns.pop(fd, None)
        if entry is None:
            return
        conn, _, timer = entry
        timer.cancel()
        self._loop.remove_reader(fd)
        conn.close()

    def close(self) -> None:
        for fd in list(self._conns):
            self._drop(fd)
        self._loop.remove_reader(self._sock.fileno())
        self._sock.close()
        try:
            os.unlink(self.path)
        except OSError:
            pass


def request(path: str, doc: dict[str, Any], timeout: float = 3.0) -> dict[str, Any]:
    """Send one request to the launch behind socket ``path`` (OSError when it is gone)."""
    with socket.socket(socket.AF_UNIX, socket.SOCK_STREAM) as sock:
        sock.settimeout(timeout)
        sock.connect(path)
        sock.sendall(json.dumps(doc).encode() + b"\n")
        chunks = []
        while True:
            data = sock.recv(65536)
            if not data:
                break
            chunks.append(data)
    return json.loads(b"".join(chunks))


def query(path: str, timeout: float = 3.0) -> dict[str, Any]:
    """Ask the launch behind socket ``path`` for its snapshot (OSError when it is gone)."""
    return request(path, {"op": "status"}, timeout)


def running_launches(directory: str | None = None) -> list[dict[str, Any]]:
    """Snapshots of every launch of this user that answers; stale sockets are removed."""
    directory = directory or runtime_dir()
    found = []
    for name in sorted(os.listdir(directory)):
        if not name.endswith(".sock"):
            continue
        path = os.path.join(directory, name)
        try:
            found.append({**query(path), "socket": path})
        except (ConnectionRefusedError, FileNotFoundError):
            import psutil

            pid = name[:-5].split("-")[0]     # <pid>.sock, or <pid>-<n>.sock (API runs)
            if pid.isdigit() and not psutil.pid_exists(int(pid)):
                try:
                    os.unlink(path)
                except OSError:
                    pass
        except (OSError, ValueError):
            continue
    return found


_LOOPBACK = {"localhost", "127.0.0.1", "::1", "localhost.localdomain", "ip6-localhost"}


def _master_key(uri: str) -> tuple[str, int | None]:
    """(host, port) of a master URI with every name of this machine as one host."""
    import urllib.parse

    parts = urllib.parse.urlsplit(uri)
    host = (parts.hostname or "localhost").lower()
    if host in _LOOPBACK or host.startswith("127.") or host == socket.gethostname().lower():
        host = "localhost"
    try:
        port = parts.port
    except ValueError:
        port = None
    return host, port


def same_master(a: str, b: str) -> bool:
    """True when two master URIs name the same master (localhost == 127.0.0.1 == hostname)."""
    return _master_key(a) == _master_key(b)


def launches_at(master_uri: str, directory: str | None = None) -> list[dict[str, Any]]:
    """The running launches of this user whose master is the one at ``master_uri``."""
    return [doc for doc in running_launches(directory)
            if same_master(str(doc.get("master_uri") or ""), master_uri)]


def launches_on_master(master_uri: str, timeout: float = 3.0) -> list[dict[str, Any]]:
    """Snapshots of the orchestra launches registered under /roslaunch/uris on a master.

    Entries of real roslaunch processes (no ``orchestra_status``) and dead ones are skipped.
    """
    try:
        code, _, uris = unpack_reply(
            call(master_uri, "getParam", "/orchestra_status", "/roslaunch/uris", timeout=timeout))
    except (OSError, xmlrpc.client.Error):
        raise OSError(f"no master answers at {master_uri}") from None
    if code != 1 or not isinstance(uris, dict):
        return []
    found = []
    for key in sorted(uris):
        try:
            code, _, doc = unpack_reply(
                call(str(uris[key]), "orchestra_status", "/orchestra_status", timeout=timeout))
            if code == 1:
                found.append(json.loads(doc))
        except (OSError, xmlrpc.client.Error, ValueError):
            continue
    return found


class LiveView:
    """Redraws the status table under the scrolling node output on a TTY, once a second."""

    def __init__(self, loop: EventLoop, screen, make_snapshot: Callable[[], dict[str, Any]],
                 interval: float = 1.0):
        self._loop = loop
        self._screen = screen
        self._make = make_snapshot
        self._interval = interval
        self._timer: Timer | None = None
        self._pending: Timer | None = None
        self._closed = False

    def start(self) -> None:
        self._tick()

    @staticmethod
    def _terminal() -> tuple[int, int]:
        try:
            size = os.get_terminal_size()
            return size.columns or 80, size.lines or 24   # 0 on a pty nobody sized
        except OSError:
            return 80, 24

    def changed(self) -> None:
        """A state changed: redraw soon, once for a burst of changes (100 nodes starting)."""
        if self._pending is None and not self._closed:
            self._pending = self._loop.call_later(0.1, self.refresh)

    def refresh(self) -> None:
        if self._pending is not None:
            self._pending.cancel()
            self._pending = None
        if not self._closed:
            columns, rows = self._terminal()
            lines = footer_lines(self._make()["nodes"], max(3, rows // 3))
            # a wrapped footer line would break the "cursor up N lines" erase
            self._screen.set_footer([line[:columns - 1] for line in lines])

    def _tick(self) -> None:
        self.refresh()
        if not self._closed:
            self._timer = self._loop.call_later(self._interval, self._tick)

    def close(self) -> None:
        self._closed = True
        for timer in (self._timer, self._pending):
            if timer is not None:
                timer.cancel()
        self._screen.set_footer([])
