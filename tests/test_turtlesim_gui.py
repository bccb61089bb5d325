"""turtlesim's Tk window glue, against a stand-in tkinter (no X server on test machines):
frames reach the photo as PNG, shutdown closes the window, closing the window shuts down."""
from __future__ import annotations

import base64
import sys
import types
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "packages" / "turtlesim" / "src"))

from turtlesim_core import gui  # noqa: E402
from turtlesim_core import world as W  # noqa: E402


def fake_tkinter(fail: bool = False):
    """Just enough of tkinter: after() callbacks run in order inside mainloop() until quit()."""
    tk = types.ModuleType("tkinter")
    tk.TclError = type("TclError", (Exception,), {})
    state = {"photos": [], "roots": []}

    class Tk:
        def __init__(self):
            if fail:
                raise tk.TclError("couldn't connect to display \":987\"")
            self.queue, self.running, self.protocols, self.destroyed = [], False, {}, False
            state["roots"].append(self)

        def title(self, text): self.title_text = text
        def resizable(self, *a): pass
        def protocol(self, name, fn): self.protocols[name] = fn
        def after(self, ms, fn): self.queue.append(fn)
        def quit(self): self.running = False
        def destroy(self): self.destroyed = True

        def mainloop(self):
            self.running = True
            while self.running and self.queue:
                self.queue.pop(0)()

    class PhotoImage:
        def __init__(self, width, height):
            self.size, self.data = (width, height), []
            state["photos"].append(self)

        def configure(self, data, format):
            self.data.append((format, base64.b64decode(data)))

    class Label:
        def __init__(self, root, image, borderwidth): pass
        def pack(self): pass

    tk.Tk, tk.PhotoImage, tk.Label = Tk, PhotoImage, Label
    return tk, state


def test_window_shows_rendered_frames_as_png_until_shutdown(monkeypatch):
    tk, state = fake_tkinter()
    monkeypatch.setitem(sys.modules, "tkinter", tk)
    world = W.World()
    world.reset(W.DEFAULT_BACKGROUND)
    frames = []

    def frame():
        frames.append(1)
        return world.render()

    gui.run_window("TurtleSim", frame, should_close=lambda: len(frames) >= 4,
                   on_close=lambda: pytest.fail("not closed by the user"))
    photo = state["photos"][0]
    assert photo.size == (500, 500)
    assert len(photo.data) == 3 and all(fmt == "png" and png.startswith(b"\x89PNG")
                                        for fmt, png in photo.data)
    assert state["roots"][0].destroyed and state["roots"][0].title_text == "TurtleSim"


def test_closing_the_window_signals_shutdown(monkeypatch):
    tk, state = fake_tkinter()
    monkeypatch.setitem(sys.modules, "tkinter", tk)
    closed = []
    world = W.World()

    def frame():
        root = state["roots"][0]
        # the user clicks the close box after a frame
        if state["photos"] and len(state["photos"][0].data) == 1:
            root.after(0, root.protocols["WM_DELETE_WINDOW"])
        return world.render()

    gui.run_window("TurtleSim", frame, should_close=lambda: False,
                   on_close=lambda: closed.append(True))
    assert closed == [True]


def test_unusable_display_is_reported_as_window_unavailable(monkeypatch):
    tk, _ = fake_tkinter(fail=True)
    monkeypatch.setitem(sys.modules, "tkinter", tk)
    with pytest.raises(gui.WindowUnavailable, match="couldn't connect"):
        gui.run_window("TurtleSim", W.World().render, lambda: False, lambda: None)


def test_display_available_needs_a_display_variable(monkeypatch):
    monkeypatch.delenv("DISPLAY", raising=False)
    assert not gui.display_available()
    monkeypatch.setenv("DISPLAY", ":0")
    assert gui.display_available()
