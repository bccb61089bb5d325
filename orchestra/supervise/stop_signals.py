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
import time

STOP_SIGNALS = (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)

_received: list[int] = []


def record() -> None:
    """From now on, stop signals are recorded for the supervisor instead of acted on."""
    if threading.current_thread() is threading.main_thread():
        for sig in STOP_SIGNALS:
            signal.signal(sig, _record)


def release() -> None:
    """Stop recording: stop signals act as Python's defaults again (SIGINT raises
    KeyboardInterrupt, SIGTERM and SIGHUP end the process), and one recorded meanwhile acts
    now. For a command that turns out to start nothing (``orchestra launch --dump-params``):
    there is nothing to stop in order, and nothing would take what is recorded, so a Ctrl-C
    during a slow ``command=`` param must end it at once, as it ends roslaunch."""
    if threading.current_thread() is not threading.main_thread():
        return
    signal.signal(signal.SIGINT, signal.default_int_handler)
    for other in STOP_SIGNALS[1:]:
        signal.signal(other, signal.SIG_DFL)
    for sig in take():
        signal.raise_signal(sig)


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


#: how often wait_event() looks for a recorded signal (a Ctrl-C is acted on within this)
_SLICE = 0.05


def wait_event(event: threading.Event, timeout: float | None = None) -> bool:
    """Wait until ``event`` is set (True), ``timeout`` passes or a stop signal is recorded
    (False; ``pending()`` tells which). For waits outside the supervisor's loop, such as
    ``orchestra test`` waiting for a test. In slices, because the handler cannot set the
    event itself: an Event's lock may be held by the very wait the signal interrupts."""
    deadline = None if timeout is None else time.monotonic() + timeout
    while not _received:
        left = _SLICE if deadline is None else min(_SLICE, deadline - time.monotonic())
        if left <= 0:
            return event.is_set()
        if event.wait(left):
            return True
    return event.is_set()


def name(signum: int) -> str:
    """``SIGINT`` for 2: how a stop signal is named to the user."""
    return signal.Signals(signum).name
