"""Where a node's stdout/stderr go: the console (prefixed, coloured on a TTY) and log files.

Routing follows roslaunch's ``output=`` semantics (``log``: stdout to the file only, stderr
to file and console; ``screen``: console only) plus ``both``. Files receive the raw bytes the
moment they are read and are flushed at once, so whatever a node wrote before it crashed
(or before orchestra itself was killed) is on disk. The console receives whole lines, each
prefixed with the node name so interleaved nodes stay readable.
"""
from __future__ import annotations

import collections
import os
import sys
import zlib
from typing import BinaryIO

from orchestra.rosdirs import log_dir_root
from orchestra.supervise.process import OutputMode

MAX_LINE = 65536   # console bytes held back waiting for a newline
RECENT_LINES = 200  # per node, for the interactive view and exit reasons

_COLOURS = (31, 32, 33, 34, 35, 36, 91, 92, 93, 94, 95, 96)


def prepare_run_log_dir(run_id: str, environ: dict[str, str] | None = None) -> str:
    """Create ``<log root>/<run_id>`` and point ``<log root>/latest`` at it (as roslaunch)."""
    root = log_dir_root(environ)
    run_dir = os.path.join(root, run_id)
    os.makedirs(run_dir, exist_ok=True)
    latest = os.path.join(root, "latest")
    tmp = f"{latest}.{os.getpid()}.tmp"
    try:
        if os.path.lexists(tmp):
            os.unlink(tmp)
        os.symlink(run_id, tmp)
        os.replace(tmp, latest)          # atomic: readers never see a missing link
    except OSError:
        pass                             # e.g. 'latest' is a real directory: leave it
    return run_dir


class RotatingFile:
    """An append-only log file rotated by size: ``x.log`` -> ``x.log.1`` -> ... ``x.log.N``."""

    def __init__(self, path: str, max_bytes: int = 0, backups: int = 5):
        self.path = path
        self.max_bytes = max_bytes
        self.backups = backups
        self._fh: BinaryIO | None = None
        self._size = 0

    def _open(self) -> BinaryIO:
        if self._fh is None:
            self._fh = open(self.path, "ab")
            self._size = self._fh.tell()
        return self._fh

    def touch(self) -> None:
        self._open()

    def _rotate(self) -> None:
        self.close()
        for i in range(self.backups - 1, 0, -1):
            src = f"{self.path}.{i}"
            if os.path.exists(src):
                os.replace(src, f"{self.path}.{i + 1}")
        if self.backups > 0:
            os.replace(self.path, f"{self.path}.1")
        else:
            os.unlink(self.path)

    def write(self, data: bytes) -> None:
        """Append ``data``; when it would pass ``max_bytes``, rotate at a line boundary."""
        while data:
            fh = self._open()
            chunk = data
            if self.max_bytes and self._size + len(data) > self.max_bytes:
                room = self.max_bytes - self._size
                cut = data.rfind(b"\n", 0, room) + 1 if room > 0 else 0
                if cut == 0 and self._size == 0:
                    cut = max(room, 1)      # one line longer than the limit: split it
                if cut == 0:
                    self._rotate()
                    continue
                chunk = data[:cut]
            fh.write(chunk)
            self._size += len(chunk)
            data = data[len(chunk):]
        if self._fh is not None:
            self._fh.flush()

    def close(self) -> None:
        if self._fh is not None:
            self._fh.close()
            self._fh = None


class Screen:
    """The console: node lines go to our stdout/stderr with a ``[name]`` prefix.

    A status footer (the live table) can be kept under the scrolling lines on a TTY: every
    write erases it, prints the lines, and draws it again.
    """

    def __init__(self, out: BinaryIO | None = None, err: BinaryIO | None = None,
                 colour: bool | None = None):
        self.out = out if out is not None else sys.stdout.buffer
        self.err = err if err is not None else sys.stderr.buffer
        if colour is None:
            colour = _isatty(self.out) and os.environ.get("NO_COLOR") is None
        self.colour = colour
        self._footer: list[str] = []
        self._footer_drawn = 0

    def prefix(self, name: str) -> bytes:
        if self.colour:
            code = _COLOURS[zlib.crc32(name.encode()) % len(_COLOURS)]
            return f"\x1b[{code}m[{name}]\x1b[0m ".encode()
        return f"[{name}] ".encode()

    def _erase_footer(self) -> None:
        if self._footer_drawn:
            self.out.write(b"\x1b[%dA\x1b[J" % self._footer_drawn)
            self._footer_drawn = 0

    def _draw_footer(self) -> None:
        if self._footer:
            self.out.write("".join(line + "\n" for line in self._footer).encode())
            self._footer_drawn = len(self._footer)

    def write_lines(self, data: bytes, stream: str) -> None:
        """Write already-prefixed complete lines to the console's stdout or stderr."""
        target = self.err if stream == "err" else self.out
        try:
            if self._footer_drawn:
                self._erase_footer()
                self.out.flush()
                target.write(data)
                target.flush()
                self._draw_footer()
                self.out.flush()
            else:
                target.write(data)
                target.flush()
        except (BrokenPipeError, ValueError):
            pass

    def message(self, text: str, err: bool = False) -> None:
        """orchestra's own console messages (started, died, stopping...)."""
        self.write_lines((text.rstrip("\n") + "\n").encode(), "err" if err else "out")

    def set_footer(self, lines: list[str]) -> None:
        try:
            self._erase_footer()
            self._footer = list(lines)
            self._draw_footer()
            self.out.flush()
        except (BrokenPipeError, ValueError):
            pass


def _isatty(stream: BinaryIO) -> bool:
    try:
        return stream.isatty()
    except (AttributeError, ValueError):
        return False


class NodeOutput:
    """Collects one node's two streams across all its runs (respawns append to the same files)."""

    def __init__(self, name: str, mode: OutputMode, screen: Screen, log_dir: str | None,
                 log_name: str | None, max_bytes: int = 0, backups: int = 5):
        self.name = name
        self.mode = mode
        self.screen = screen
        self._prefix = screen.prefix(name)
        self._partial = {"out": b"", "err": b""}
        # the last lines of both streams (whatever the output mode): what the interactive
        # view shows for a node and how an exit is explained (MemoryError under memory-limit)
        self.recent: collections.deque[bytes] = collections.deque(maxlen=RECENT_LINES)
        self.muted = False               # by hand: output still logged, not shown
        self.files: dict[str, RotatingFile] = {}
        if log_dir and log_name and mode in (OutputMode.LOG, OutputMode.BOTH):
            for stream, suffix in (("out", "stdout"), ("err", "stderr")):
                path = os.path.join(log_dir, f"{log_name}-{suffix}.log")
                self.files[stream] = RotatingFile(path, max_bytes, backups)

    def started(self) -> None:
        """The node started: its log files exist from now on, like roslaunch's (created
        here, not at construction, so a launch opens them after its nodes are spawned)."""
        for log in self.files.values():
            try:
                log.touch()
            except OSError:
                pass

    def _to_screen(self, stream: str) -> bool:
        return self.mode != OutputMode.LOG or stream == "err"

    def feed(self, stream: str, data: bytes) -> None:
        """New bytes read from the node's ``out`` or ``err`` pipe."""
        log = self.files.get(stream)
        if log is not None:
            try:
                log.write(data)
            except OSError:
                pass
        buf = self._partial[stream] + data
        cut = buf.rfind(b"\n")
        if cut < 0:
            if len(buf) > MAX_LINE:      # no newline for too long (progress bars): show it
                self._partial[stream] = b""
                self._lines(stream, [buf])
            else:
                self._partial[stream] = buf
            return
        self._partial[stream] = buf[cut + 1:]
        self._lines(stream, buf[:cut].split(b"\n"))

    def _lines(self, stream: str, lines: list[bytes]) -> None:
        """Complete lines: kept as the node's recent output, shown unless muted or logged."""
        self.recent.extend(lines)
        if self._to_screen(stream) and not self.muted:
            self.screen.write_lines(b"".join(self._prefix + line + b"\n" for line in lines),
                                    stream)

    def end(self, stream: str) -> None:
        """The pipe reached EOF: a last line without newline is still shown."""
        rest = self._partial[stream]
        self._partial[stream] = b""
        if rest:
            self._lines(stream, [rest])

    def close(self) -> None:
        for log in self.files.values():
            log.close()
