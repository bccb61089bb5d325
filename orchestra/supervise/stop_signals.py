"""Stop signals (SIGINT, SIGTERM, SIGHUP) that arrive before the supervisor owns them.

``orchestra launch`` spends its first fraction of a second importing and resolving. A Ctrl-C
there raised KeyboardInterrupt wherever Python happened to be: once inside an import-lock
callback, where Python reports and drops exceptions, so the launch went on running as if no
Ctrl-C had come. So the launch command records stop signals from its start (the handler only
appends the number: no lock, no exception, nothing to lose), and the supervisor, when it
installs its own handlers, takes what was recorded and stops at once, as for a Ctrl-C during
the run. Only the handler changes: the signal mask is untouched, children inherit none.
"""
from __future__ import annotations

import signal
import threading

STOP_SIGNALS = (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)

_received: list[int] = []


def record() -> None:
    """From now on, stop signals are recorded for the supervisor instead of acted on."""
    if threading.current_thread() is threading.main_thread():
        for sig in STOP_SIGNALS:
            signal.signal(sig, _record)


def _record(signum: int, frame: object) -> None:
    _received.append(signum)   # atomic; safe even when it interrupts itself


def pending() -> bool:
    """A stop signal was recorded and not taken yet (for waits before the supervisor)."""
    return bool(_received)


def take() -> list[int]:
    """The recorded stop signals, oldest first; forgets them."""
    taken = list(_received)
    del _received[:len(taken)]
    return taken
