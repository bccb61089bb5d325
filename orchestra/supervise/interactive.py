"""The interactive terminal view (``orchestra launch --ui``): rosmon's keys on the live table.

Node output keeps scrolling above; below it, the table of nodes (rendered with rich) with one
selected row, and a key line. Keys are read from the terminal by the supervisor's own loop
(no thread), so a key acts on the supervisor exactly like a control request does:

    Up/Down, k/j   select a node            s   stop / start the selected node
    r              restart it               S   stop it even when required (force)
    m              mute / unmute its output l   show / hide its last output lines
    /              filter by name (Enter applies, Esc clears)
    q              quit: stop every node in order (as Ctrl-C)

It takes the keyboard, so it is opt-in: by roslaunch's contract the terminal belongs to the
nodes (``turtle_teleop_key`` reads its arrow keys from it). Without a terminal on both stdin
and stdout it is not started and the output stays plain.
"""
from __future__ import annotations

import io
import logging
import os
import termios
import tty
from collections.abc import Callable
from typing import Any

from rich.console import Console
from rich.table import Table
from rich.text import Text

from orchestra.supervise.loop import EventLoop
from orchestra.supervise.output import Screen
from orchestra.supervise.status import format_duration, format_size
from orchestra.supervise.supervisor import ControlError, Supervisor

logger = logging.getLogger(__name__)

KEYS_HELP = ("↑/↓ select  s stop/start  r restart  m mute  l log  / filter  q quit")
LOG_LINES = 8
_STATE_STYLE = {"RUNNING": "green", "STOPPED": "yellow", "STOPPING": "yellow",
                "BACKOFF": "magenta", "FAILED": "bold red", "EXITED": "dim", "STARTING": "cyan"}
_ARROWS = {b"\x1b[A": "up", b"\x1b[B": "down", b"\x1bOA": "up", b"\x1bOB": "down"}


def terminal_ok(stdin: Any, stdout: Any) -> bool:
    """Both ends are terminals: keys can be read and the table drawn."""
    try:
        return stdin.isatty() and stdout.isatty()
    except (AttributeError, ValueError):
        return False


def parse_keys(data: bytes) -> list[str]:
    """Terminal bytes -> key names (``up``, ``down``, ``esc``, ``enter``, ``backspace`` or the
    character itself); unknown escape sequences are dropped."""
    keys: list[str] = []
    i = 0
    while i < len(data):
        if data[i:i + 1] == b"\x1b":
            seq = data[i:i + 3]
            if seq in _ARROWS:
                keys.append(_ARROWS[seq])
                i += 3
                continue
            if len(data) > i + 1 and data[i + 1:i + 2] in (b"[", b"O"):
                i += 3           # another sequence (right/left/home...): ignored
                continue
            keys.append("esc")
            i += 1
            continue
        byte = data[i]
        i += 1
        if byte in (10, 13):
            keys.append("enter")
        elif byte in (8, 127):
            keys.append("backspace")
        elif 32 <= byte < 127:
            keys.append(chr(byte))
    return keys


class InteractiveView:
    """Draws the selectable table under the output and turns keys into control actions."""

    def __init__(self, loop: EventLoop, supervisor: Supervisor, screen: Screen,
                 make_snapshot: Callable[[], dict[str, Any]], stdin_fd: int,
                 interval: float = 1.0):
        self._loop = loop
        self._sup = supervisor
        self._screen = screen
        self._make = make_snapshot
        self._fd = stdin_fd
        self._interval = interval
        self._saved: list[Any] | None = None
        self._timer: Any = None
        self._pending: Any = None
        self._closed = False
        self.selected = 0
        self.filter = ""
        self.editing: str | None = None      # the filter being typed, None when not typing
        self.show_log = False
        self.message = ""

    # ------------------------------------------------------------------ life cycle

    def start(self) -> None:
        try:
            self._saved = termios.tcgetattr(self._fd)
            tty.setcbreak(self._fd)
        except termios.error as exc:
            logger.warning("no interactive view: %s", exc)
            return
        self._loop.add_reader(self._fd, self._on_input)
        self._tick()

    def close(self) -> None:
        self._closed = True
        for timer in (self._timer, self._pending):
            if timer is not None:
                timer.cancel()
        self._loop.remove_reader(self._fd)
        if self._saved is not None:
            try:
                termios.tcsetattr(self._fd, termios.TCSADRAIN, self._saved)
            except termios.error:
                pass
        self._screen.set_footer([])

    def changed(self) -> None:
        if self._pending is None and not self._closed:
            self._pending = self._loop.call_later(0.1, self.refresh)

    def _tick(self) -> None:
        self.refresh()
        if not self._closed:
            self._timer = self._loop.call_later(self._interval, self._tick)

    # ------------------------------------------------------------------ keys

    def _on_input(self) -> None:
        try:
            data = os.read(self._fd, 1024)
        except (BlockingIOError, InterruptedError):
            return
        except OSError:
            data = b""
        if not data:                      # the terminal went away: stop listening
            self._loop.remove_reader(self._fd)
            return
        for key in parse_keys(data):
            self.press(key)
        self.refresh()

    def visible(self) -> list[str]:
        names = [p.spec.name for p in self._sup.procs]
        return [n for n in names if self.filter.lower() in n.lower()]

    def current(self) -> str | None:
        shown = self.visible()
        if not shown:
            return None
        self.selected = max(0, min(self.selected, len(shown) - 1))
        return shown[self.selected]

    def press(self, key: str) -> None:
        """One key: what it does is in the module docstring."""
        if self.editing is not None:
            self._edit_filter(key)
            return
        name = self.current()
        if key in ("up", "k"):
            self.selected = max(0, self.selected - 1)
        elif key in ("down", "j"):
            self.selected += 1
        elif key == "/":
            self.editing = self.filter
        elif key == "q":
            self.message = "stopping every node"
            self._sup.request_stop("q pressed in the interactive view")
        elif name is None:
            return
        elif key in ("s", "S", "r"):
            self.message = self._act(key, name)
        elif key == "m":
            output = self._sup.outputs[name]
            output.muted = not output.muted
            self.message = f"{'muted' if output.muted else 'unmuted'} {name}"
        elif key == "l":
            self.show_log = not self.show_log

    def _act(self, key: str, name: str) -> str:
        proc = self._sup.by_name(name)
        try:
            if key == "r":
                return self._sup.restart_process(name)
            if proc.state.value in ("STOPPED", "EXITED", "FAILED"):
                return self._sup.start_process(name)
            return self._sup.stop_process(name, force=key == "S")
        except ControlError as exc:
            return str(exc).replace("--force", "S")

    def _edit_filter(self, key: str) -> None:
        assert self.editing is not None
        if key == "enter":
            self.filter, self.editing, self.selected = self.editing, None, 0
        elif key == "esc":
            self.filter, self.editing, self.selected = "", None, 0
        elif key == "backspace":
            self.editing = self.editing[:-1]
        elif len(key) == 1:
            self.editing += key

    # ------------------------------------------------------------------ drawing

    def refresh(self) -> None:
        if self._pending is not None:
            self._pending.cancel()
            self._pending = None
        if self._closed:
            return
        try:
            size = os.get_terminal_size()
            columns, rows = size.columns or 80, size.lines or 24
        except OSError:
            columns, rows = 80, 24
        lines = self.render(columns, max(6, rows // 2))
        self._screen.set_footer(lines)

    def render(self, columns: int, max_lines: int) -> list[str]:
        """The footer as ANSI lines (rich renders; the Screen keeps it under the output)."""
        nodes = {n["name"]: n for n in self._make()["nodes"]}
        shown = self.visible()
        current = self.current()
        table = Table(box=None, pad_edge=False, show_edge=False, expand=False,
                      header_style="bold")
        for column, justify in (("NODE", "left"), ("STATE", "left"), ("PID", "right"),
                                ("RESTARTS", "right"), ("UPTIME", "right"), ("CPU%", "right"),
                                ("RSS", "right"), ("", "left")):
            table.add_column(column, justify=justify, no_wrap=True)  # type: ignore[arg-type]
        budget = max(1, max_lines - 3 - (LOG_LINES if self.show_log else 0))
        first = max(0, min(self.selected - budget + 1, len(shown) - budget))
        for name in shown[first:first + budget]:
            n = nodes[name]
            notes = []
            if self._sup.outputs[name].muted:
                notes.append("muted")
            if n["state"] != "RUNNING" and n.get("reason"):
                notes.append(n["reason"])
            table.add_row(
                ("> " if name == current else "  ") + name,
                Text(n["state"], style=_STATE_STYLE.get(n["state"], "")),
                "-" if n["pid"] is None else str(n["pid"]), str(n["restarts"]),
                format_duration(n["uptime"]) if n["pid"] is not None else "-",
                "-" if n["cpu_percent"] is None else f"{n['cpu_percent']:.1f}",
                format_size(n["rss"]), "; ".join(notes),
                style="reverse" if name == current else None)
        status = (f"filter: {self.editing}_" if self.editing is not None
                  else (f"[filter: {self.filter}] " if self.filter else "") + KEYS_HELP)
        parts: list[Any] = [table]
        if self.show_log and current is not None:
            recent = list(self._sup.outputs[current].recent)[-LOG_LINES:]
            parts.append(Text(f"--- last output of {current} ---", style="bold"))
            parts += [Text(line.decode("utf-8", "replace")) for line in recent]
        parts.append(Text(status + (f"  | {self.message}" if self.message else ""),
                          style="bold cyan"))
        buffer = io.StringIO()
        console = Console(file=buffer, width=columns - 1, force_terminal=True,
                          color_system="standard", highlight=False, soft_wrap=False)
        for part in parts:
            console.print(part, overflow="crop", no_wrap=True, crop=True)
        return buffer.getvalue().rstrip("\n").split("\n")
