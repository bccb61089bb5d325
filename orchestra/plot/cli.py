"""``orchestra plot TOPIC/FIELD[:FIELD...]...``: rqt_plot on a terminal.

From a bag (``--bag``: bag time on x) or live (subscribed as a node: receipt time on x);
to a file (``--out plot.png|svg``, live for ``--duration`` seconds) or, where there is a
display, to a window that follows the data.
"""
from __future__ import annotations

import os
import queue
import threading
import time

import click

from orchestra.errors import Location, OrchestraError
from orchestra.plot.series import Series, SpecError, parse_spec, pick


class PlotError(OrchestraError):
    """The plot cannot be made as asked."""


def series_from_bag(path: str, specs: tuple[str, ...]) -> list[Series]:
    from orchestra.bag.cli import bag_errors
    from orchestra.bag.reader import BagReader
    from orchestra.node.decode import RawDecoder
    with bag_errors(path):
        with BagReader(path) as reader:
            topics = sorted({c.topic for c in reader.connections})
            series = _parse(specs, topics)
            wanted = {s.topic for s in series}
            decoder = RawDecoder()
            first = reader.start_time
            for conn, stamp, data in reader.messages(wanted):
                msg = decoder.decode(conn.header, data)
                _add(series, conn.topic, msg, (stamp - first) / 1e9)
    return series


def _parse(specs: tuple[str, ...], topics: list[str]) -> list[Series]:
    out: list[Series] = []
    try:
        for spec in specs:
            out += parse_spec(spec, topics)
    except SpecError as exc:
        raise PlotError(str(exc)) from None
    return out


def _add(series: list[Series], topic: str, msg, t: float) -> None:
    for s in series:
        if s.topic == topic:
            try:
                value = pick(msg, s.path, s.label)
            except SpecError as exc:
                raise PlotError(str(exc)) from None
            s.times.append(t)
            s.values.append(value)


class LiveSource:
    """Raw subscriptions that queue decoded messages with their receipt time."""

    def __init__(self, series: list[Series]):
        import orchestra.node as rospy
        from orchestra.node.decode import RawDecoder
        self.series = series
        self.inbox: queue.Queue = queue.Queue()
        self.decoder = RawDecoder()
        self.start = time.monotonic()
        self.subs = [rospy.Subscriber(t, rospy.AnyMsg, self._on, callback_args=t,
                                      queue_size=0)
                     for t in sorted({s.topic for s in series})]

    def _on(self, raw, topic: str) -> None:
        self.inbox.put((time.monotonic() - self.start, topic, raw))

    def refresh(self) -> None:
        while True:
            try:
                t, topic, raw = self.inbox.get_nowait()
            except queue.Empty:
                return
            _add(self.series, topic, self.decoder(raw), t)


def _has_display() -> bool:
    return bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))


@click.command("plot")
@click.argument("specs", nargs=-1, required=True)
@click.option("--bag", "bag_path", default=None, help="Plot from this bag instead of live.")
@click.option("--out", default=None, help="Write the picture here (.png, .svg, .pdf).")
@click.option("--duration", default=10.0, type=click.FloatRange(min=0, min_open=True),
              show_default=True, help="Live to --out: seconds of data to collect.")
@click.option("--title", default="", help="A title above the plot.")
def plot(specs: tuple[str, ...], bag_path: str | None, out: str | None, duration: float,
         title: str) -> None:
    """Plot numeric fields: TOPIC/FIELD, several fields as TOPIC/F1:F2 (as rqt_plot).

    Examples: orchestra plot /turtle1/pose/x:y --out pose.png --duration 5;
    orchestra plot --bag run.bag /turtle1/pose/x /turtle1/pose/y --out pose.png"""
    from orchestra.plot import figure
    if out is not None:
        folder = os.path.dirname(os.path.abspath(out))
        if not os.path.isdir(folder):
            raise PlotError(f"folder {folder} does not exist", Location(out))
        if os.path.splitext(out)[1].lower() not in (".png", ".svg", ".pdf"):
            raise PlotError("the picture must end in .png, .svg or .pdf", Location(out))
    elif not _has_display():
        raise PlotError("no display here: write a picture with --out FILE.png")
    if bag_path is not None:
        series = series_from_bag(bag_path, specs)
        if out is not None:
            figure.save(series, out, title or os.path.basename(bag_path))
        else:
            figure.show_live(series, lambda: None, title)
        return
    _plot_live(specs, out, duration, title)


def _plot_live(specs: tuple[str, ...], out: str | None, duration: float, title: str) -> None:
    from orchestra.node import introspect
    from orchestra.node.tool import (
        master_uri,
        split_field_path,
        start_cli_node,
        stop_cli_node,
        wait_for_topic,
    )
    from orchestra.plot import figure
    start_cli_node()
    try:
        state = introspect.system_state(master_uri())
        for spec in specs:   # as rqt_plot: a topic not there yet is waited for, not an error
            first = "/" + spec.split(":")[0].lstrip("/")
            topic, _ = split_field_path(first, state.topics)
            if topic not in state.topics:
                click.echo(f"waiting for topic {first} ...", err=True)
                wait_for_topic(first)
                state = introspect.system_state(master_uri())
        series = _parse(specs, sorted(state.topics))
        source = LiveSource(series)
        if out is None:
            figure.show_live(series, source.refresh, title)
            return
        stop = threading.Event()
        try:
            stop.wait(duration)
        except KeyboardInterrupt:
            pass
        source.refresh()
        for s in series:
            if not s.times:
                click.echo(f"warning: no data for {s.label} in {duration:g} s", err=True)
        figure.save(series, out, title)
    finally:
        stop_cli_node("plot done")
