"""The optional Tk window: shows the rendered canvas, refreshed ~30 times a second.

Tk must own the main thread, so in GUI mode the simulator ticks on a worker thread and this
module only pulls frames. Frames go to Tk as base64 PNG (Tk 8.6 reads PNG natively), reusing
the snapshot encoder instead of a second image path.
"""
from __future__ import annotations

import base64
import os
from collections.abc import Callable

from turtlesim_core.canvas import Canvas
from turtlesim_core.png import encode_png

REFRESH_MS = 33


class WindowUnavailable(Exception):
    """DISPLAY is set but no window can be opened there (no X server, no permission)."""


def display_available() -> bool:
    """Whether a window can be opened at all: a DISPLAY and an importable tkinter."""
    if not os.environ.get("DISPLAY"):
        return False
    try:
        import tkinter  # noqa: F401
    except ImportError:
        return False
    return True


def run_window(title: str, frame: Callable[[], Canvas], should_close: Callable[[], bool],
               on_close: Callable[[], None]) -> None:
    """Block in Tk's main loop until the window is closed or ``should_close()`` turns true."""
    import tkinter as tk

    try:
        root = tk.Tk()
    except tk.TclError as exc:
        raise WindowUnavailable(str(exc)) from None
    root.title(title)
    root.resizable(False, False)
    first = frame()
    photo = tk.PhotoImage(width=first.width, height=first.height)
    label = tk.Label(root, image=photo, borderwidth=0)
    label.pack()

    def refresh() -> None:
        if should_close():
            root.quit()
            return
        canvas = frame()
        png = encode_png(canvas.width, canvas.height, canvas.pixels)
        photo.configure(data=base64.b64encode(png), format="png")
        root.after(REFRESH_MS, refresh)

    def close() -> None:
        on_close()
        root.quit()

    root.protocol("WM_DELETE_WINDOW", close)
    root.after(0, refresh)
    try:
        root.mainloop()
    finally:
        root.destroy()
