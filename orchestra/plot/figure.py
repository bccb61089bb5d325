"""Draw series with matplotlib: a file (Agg) or a live window that follows new points."""
from __future__ import annotations

from collections.abc import Callable
from typing import Any

from orchestra.plot.series import Series


def _pyplot(backend: str | None) -> Any:
    import matplotlib
    if backend is not None:
        matplotlib.use(backend)
    import matplotlib.pyplot as plt
    return plt


def draw(series: list[Series], title: str = "", backend: str | None = "Agg") -> Any:
    """A figure with one line per series (time in seconds on x); returns the Figure."""
    plt = _pyplot(backend)
    fig, ax = plt.subplots(figsize=(8, 4.5), dpi=100)
    for s in series:
        ax.plot(s.times, s.values, label=s.label, linewidth=1.5)
    ax.set_xlabel("time (s)")
    ax.grid(True, alpha=0.3)
    if title:
        ax.set_title(title)
    if series:
        ax.legend(loc="best")
    fig.tight_layout()
    return fig


def save(series: list[Series], out: str, title: str = "") -> Any:
    """Write the picture to ``out`` (format from its suffix: png, svg, pdf)."""
    fig = draw(series, title)
    fig.savefig(out, dpi=fig.dpi)
    return fig


def show_live(series: list[Series], refresh: Callable[[], None], title: str = "") -> None:
    """A window redrawn every 100 ms with the points ``refresh`` added, until closed."""
    plt = _pyplot(None)
    from matplotlib.animation import FuncAnimation
    fig = draw(series, title, backend=None)
    ax = fig.axes[0]

    def update(_frame: int) -> list:
        refresh()
        for line, s in zip(ax.get_lines(), series, strict=True):
            line.set_data(s.times, s.values)
        ax.relim()
        ax.autoscale_view()
        return list(ax.get_lines())

    anim = FuncAnimation(fig, update, interval=100, cache_frame_data=False)
    plt.show()
    del anim
