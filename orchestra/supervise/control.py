"""Live control of a running launch: which processes a request names, and what it does.

Requests arrive as JSON documents on the launch's user-only Unix socket (status.py serves
it; ``{"op": "status"}`` is the snapshot). Every other op acts on processes named by exact
name, by name without the leading slash, by namespace (``/robot1`` or ``/robot1/`` = every
process below it) or by glob (``/cam*``):

    {"op": "stop" | "start" | "restart", "names": [...], "force": false}
    {"op": "signal", "names": [...], "signal": "SIGUSR1"}
    {"op": "mute" | "unmute", "names": [...]}

The answer is ``{"ok": true, "done": [[name, what happened], ...]}`` or
``{"ok": false, "error": "...", "unknown": [...]}``. A request naming an unknown process does
nothing at all (no half-done group). Requests run on the supervisor's own loop, so they see
a consistent state and never race with an exit being handled.
"""
from __future__ import annotations

import fnmatch
import signal
from typing import Any

from orchestra.suggest import did_you_mean
from orchestra.supervise.supervisor import ControlError, Supervisor

OPS = ("stop", "start", "restart", "signal", "mute", "unmute")


class UnknownProcess(ControlError):
    """A name matching no process of the launch; carries the unknown words."""

    def __init__(self, message: str, unknown: list[str]):
        super().__init__(message)
        self.unknown = unknown


def matches(pattern: str, names: list[str]) -> list[str]:
    """The names ``pattern`` selects: exact, namespace (prefix ``/ns/``) or glob."""
    full = pattern if pattern.startswith("/") else "/" + pattern
    if full in names:
        return [full]
    if any(ch in full for ch in "*?["):
        return [n for n in names if fnmatch.fnmatchcase(n, full)]
    prefix = full.rstrip("/") + "/"
    return [n for n in names if n.startswith(prefix)]


def select(patterns: list[str], names: list[str]) -> list[str]:
    """Every name the patterns select, in launch order; UnknownProcess names the rest."""
    chosen: set[str] = set()
    unknown = []
    for pattern in patterns:
        found = matches(pattern, names)
        if not found:
            unknown.append(pattern)
        chosen.update(found)
    if unknown:
        hints = "".join(f"no node {u} in this launch{did_you_mean(u, names)}\n"
                        for u in unknown).rstrip("\n")
        raise UnknownProcess(hints, unknown)
    return [n for n in names if n in chosen]


def parse_signal(value: Any) -> int:
    """``SIGUSR1`` / ``USR1`` / ``10`` -> the signal number (ControlError when unknown)."""
    text = str(value).upper()
    try:
        if text.isdigit():
            return int(signal.Signals(int(text)))
        return int(signal.Signals[text if text.startswith("SIG") else "SIG" + text])
    except (KeyError, ValueError):
        raise ControlError(f"unknown signal {value!r}") from None


def handle(supervisor: Supervisor, request: dict[str, Any]) -> dict[str, Any]:
    """Carry out one control request (not ``status``) and describe the outcome."""
    op = request.get("op")
    if op not in OPS:
        return {"ok": False, "error": f"unknown op {op!r}; expected one of {', '.join(OPS)}"}
    patterns = request.get("names")
    if not isinstance(patterns, list) or not patterns \
            or not all(isinstance(p, str) and p for p in patterns):
        return {"ok": False, "error": "'names' must be a non-empty list of node names"}
    try:
        names = select(patterns, [p.spec.name for p in supervisor.procs])
        sig = parse_signal(request.get("signal", "")) if op == "signal" else 0
        if op == "stop" and not request.get("force"):
            required = [n for n in names if supervisor.by_name(n).spec.required]
            if required:   # refuse the whole group: nothing half-done
                raise ControlError(f"{', '.join(required)}: required (its end stops the "
                                   "launch); use --force to stop it anyway")
        done = []
        for name in names:
            if op == "stop":
                what = supervisor.stop_process(name, force=bool(request.get("force")))
            elif op == "start":
                what = supervisor.start_process(name)
            elif op == "restart":
                what = supervisor.restart_process(name)
            elif op == "signal":
                what = supervisor.signal_process(name, sig)
            else:
                supervisor.outputs[name].muted = op == "mute"
                what = f"{op}d {name}"
            done.append([name, what])
    except UnknownProcess as exc:
        return {"ok": False, "error": str(exc), "unknown": exc.unknown}
    except ControlError as exc:
        return {"ok": False, "error": str(exc)}
    return {"ok": True, "done": done}
