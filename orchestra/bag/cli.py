"""``orchestra bag ...``: rosbag's commands on orchestra's bag library and node runtime.

This is the edge: it parses options as rosbag does, turns the library's errors into one
line naming the file (exit 2), draws the progress line and reads the keyboard of ``play``
(only when stdin is a terminal).
"""
from __future__ import annotations

import contextlib
import os
import queue
import re
import select
import signal
import sys
import threading
import time
from collections.abc import Iterator

import click

from orchestra.errors import Location, OrchestraError


class BagError(OrchestraError):
    """A bag the user named cannot be used; the message says why."""


@contextlib.contextmanager
def bag_errors(path: str) -> Iterator[None]:
    """Library errors about ``path`` as one line: ``PATH: what is wrong``."""
    from orchestra.bag.reader import BagUnindexed, NotABag
    from orchestra.bag.records import BagFormatError
    try:
        yield
    except NotABag as exc:
        raise BagError(f"not a ROS 1 bag: {exc}", Location(path)) from None
    except BagUnindexed as exc:
        raise BagError(f"{exc}; `orchestra bag reindex {path}` may help",
                       Location(path)) from None
    except BagFormatError as exc:
        raise BagError(f"damaged bag: {exc}; `orchestra bag reindex {path}` may help",
                       Location(path)) from None
    except FileNotFoundError:
        raise BagError("no such file", Location(path)) from None
    except OSError as exc:
        raise BagError(f"cannot read: {exc.strerror or exc}", Location(path)) from None


@click.group()
def bag() -> None:
    """Record, play and inspect ROS 1 bags (rosbag)."""


# --- info -------------------------------------------------------------------------------------

@bag.command("info")
@click.argument("files", nargs=-1, required=True)
@click.option("-y", "--yaml", "as_yaml", is_flag=True, help="Print information as YAML.")
@click.option("--freq", is_flag=True, help="Show each topic's median message rate (reads "
              "the whole bag).")
def info(files: tuple[str, ...], as_yaml: bool, freq: bool) -> None:
    """Summarize the contents of one or more bag files (as rosbag info)."""
    from orchestra.bag import info as info_mod
    from orchestra.bag.reader import BagReader
    for i, path in enumerate(files):
        with bag_errors(path):
            with BagReader(path) as reader:
                summary = info_mod.summarize(path, reader, freq)
        click.echo(info_mod.yaml_text(summary) if as_yaml else info_mod.text(summary))
        if i < len(files) - 1:
            click.echo("---")


# --- reindex, compress, decompress, filter ---------------------------------------------------

@bag.command("reindex")
@click.argument("files", nargs=-1, required=True)
@click.option("--no-backup", is_flag=True, help="Do not keep NAME.orig.bag.")
@click.option("-q", "--quiet", is_flag=True, help="Say nothing on success.")
def reindex(files: tuple[str, ...], no_backup: bool, quiet: bool) -> None:
    """Rebuild the index of bags that were not closed (a killed recorder, a full disk)."""
    from orchestra.bag.reindex import reindex as do_reindex
    for path in files:
        with bag_errors(path):
            result = do_reindex(path, backup=not no_backup)
        if not quiet:
            note = f" ({result.problem})" if result.problem else ""
            click.echo(f"{path}: {result.messages} messages in {len(result.chunks)} chunks "
                       f"indexed{note}")


def _recompress(files: tuple[str, ...], compression: str, output_dir: str | None,
                force: bool, quiet: bool) -> None:
    from orchestra.bag.compress import already, recompress
    if output_dir is not None and not os.path.isdir(output_dir):
        raise BagError("no such folder", Location(output_dir))
    for path in files:
        with bag_errors(path):
            if already(path, compression) and not force:
                if not quiet:
                    click.echo(f"{path}: already {compression}; nothing to do")
                continue
            try:
                dst = recompress(path, compression, output_dir, force)
            except FileExistsError as exc:
                raise BagError(str(exc), Location(path)) from None
        if not quiet:
            click.echo(f"{path}: written as {compression} to {dst}")


@bag.command("compress")
@click.argument("files", nargs=-1, required=True)
@click.option("-j", "--bz2", "compression", flag_value="bz2", default=True,
              help="bz2 compression (the default).")
@click.option("--lz4", "compression", flag_value="lz4", help="lz4 compression.")
@click.option("--output-dir", default=None, help="Write the result here; keep the original.")
@click.option("-f", "--force", is_flag=True, help="Overwrite NAME.orig.bag.")
@click.option("-q", "--quiet", is_flag=True)
def compress(files: tuple[str, ...], compression: str, output_dir: str | None, force: bool,
             quiet: bool) -> None:
    """Compress bags (the original is kept as NAME.orig.bag)."""
    _recompress(files, compression, output_dir, force, quiet)


@bag.command("decompress")
@click.argument("files", nargs=-1, required=True)
@click.option("--output-dir", default=None, help="Write the result here; keep the original.")
@click.option("-f", "--force", is_flag=True, help="Overwrite NAME.orig.bag.")
@click.option("-q", "--quiet", is_flag=True)
def decompress(files: tuple[str, ...], output_dir: str | None, force: bool,
               quiet: bool) -> None:
    """Decompress bags (the original is kept as NAME.orig.bag)."""
    _recompress(files, "none", output_dir, force, quiet)


@bag.command("filter")
@click.argument("inbag")
@click.argument("outbag")
@click.argument("expression")
def filter_(inbag: str, outbag: str, expression: str) -> None:
    """Write the messages of INBAG for which EXPRESSION is true to OUTBAG.

    EXPRESSION sees topic, m (the message) and t (its time), e.g.
    "topic == '/chatter' and m.data != 'x' and t.to_sec() > 1700000000". It is evaluated
    safely (a whitelist), never executed as Python."""
    from orchestra.bag.expression import ExpressionError
    from orchestra.bag.filter import filter_bag, make_filter
    try:
        expr = make_filter(expression)
    except ExpressionError as exc:
        raise BagError(f"bad filter expression: {exc}") from None
    if os.path.abspath(inbag) == os.path.abspath(outbag):
        raise BagError("the output must not be the input", Location(outbag))
    with bag_errors(inbag):
        try:
            count = filter_bag(inbag, outbag, expr)
        except ExpressionError as exc:
            raise BagError(f"filter expression failed: {exc}") from None
    click.echo(f"{outbag}: {count} messages", err=True)


# --- record -----------------------------------------------------------------------------------

_SIZE = re.compile(r"^\s*(\d+(?:\.\d+)?)\s*$")
_DURATION = re.compile(r"^\s*(\d+(?:\.\d+)?)\s*([smh]?)\s*$")


def parse_duration(text: str) -> float:
    """rosbag's durations: seconds, or with an s/m/h suffix (``30``, ``1.5m``, ``2h``)."""
    m = _DURATION.match(text)
    if not m:
        raise click.BadParameter(f"'{text}' is not a duration (e.g. 30, 1.5m, 2h)")
    return float(m.group(1)) * {"": 1, "s": 1, "m": 60, "h": 3600}[m.group(2)]


@bag.command("record")
@click.argument("topics", nargs=-1)
@click.option("-a", "--all", "all_", is_flag=True, help="Record all topics.")
@click.option("-e", "--regex", default=None, help="Record topics matching this regex.")
@click.option("-x", "--exclude", default=None, help="Do not record topics matching this.")
@click.option("-O", "--output-name", default=None, help="Record to NAME.bag.")
@click.option("-o", "--output-prefix", default=None, help="Prepend PREFIX to the bag name.")
@click.option("--split", is_flag=True, help="Split the bag at --size or --duration.")
@click.option("--size", default=None, type=float, help="With --split: MB per bag.")
@click.option("--duration", default=None, help="Record for this long (30, 1m, 2h); with "
              "--split: per bag.")
@click.option("-j", "--bz2", "compression", flag_value="bz2", help="bz2 compression.")
@click.option("--lz4", "compression", flag_value="lz4", help="lz4 compression.")
@click.option("-b", "--buffsize", default=256, type=click.IntRange(min=1),
              help="In-memory queue size in MB (default 256); the oldest is dropped.")
@click.option("--chunksize", default=768, type=click.IntRange(min=1),
              help="Chunk size in KB (default 768).")
@click.option("-l", "--limit", default=None, type=click.IntRange(min=1),
              help="Record at most this many messages per topic.")
@click.option("-q", "--quiet", is_flag=True, help="No progress line.")
def record(topics: tuple[str, ...], all_: bool, regex: str | None, exclude: str | None,
           output_name: str | None, output_prefix: str | None, split: bool,
           size: float | None, duration: str | None, compression: str | None,
           buffsize: int, chunksize: int, limit: int | None, quiet: bool) -> None:
    """Record TOPICS (or -a all, or -e REGEX) into a bag, as rosbag record."""
    from orchestra.bag.record import Recorder, RecordError, RecordOptions
    if not topics and not all_ and not regex:
        raise click.UsageError("give topics to record, or -a, or -e REGEX")
    for pattern in (regex, exclude):
        if pattern is not None:
            try:
                re.compile(pattern)
            except re.error as exc:
                raise BagError(f"bad regex '{pattern}': {exc}") from None
    seconds = parse_duration(duration) if duration is not None else None
    if split and size is None and seconds is None:
        raise click.UsageError("--split needs --size or --duration")
    opts = RecordOptions(
        topics=list(topics), all=all_, regex=regex, exclude=exclude, name=output_name,
        prefix=output_prefix, duration=None if split else seconds,
        split_size=int(size * 1024 * 1024) if split and size else None,
        split_duration=seconds if split else None, compression=compression or "none",
        buffsize=buffsize * 1024 * 1024, chunksize=chunksize * 1024, limit=limit)
    from orchestra.node.tool import master_uri, require_master
    try:
        recorder = Recorder(opts)
    except RecordError as exc:
        raise BagError(str(exc)) from None
    require_master(master_uri())
    stop = _stop_on_signals(recorder.stopping)
    try:
        recorder.start()
        progress = not quiet and sys.stderr.isatty()
        last = (time.monotonic(), 0)
        while not recorder.wait(0.5):
            if progress:
                last = _record_progress(recorder, last)
    finally:
        recorder.stop()
        stop()
        if not quiet and sys.stderr.isatty():
            click.echo("", err=True)
    if recorder.error:
        raise BagError(f"recording stopped: {recorder.error}")
    if recorder.dropped:
        click.echo(f"warning: {recorder.dropped} messages dropped (--buffsize exceeded)",
                   err=True)


def _record_progress(recorder, last: tuple[float, int]) -> tuple[float, int]:
    from orchestra.bag.info import human_size
    now = time.monotonic()
    rate = (recorder.messages - last[1]) / max(now - last[0], 1e-6)
    click.echo(f"\r[RECORDING] {recorder.path}  {recorder.messages} msgs  "
               f"{human_size(recorder.bytes)}  {rate:.1f} msg/s   ", err=True, nl=False)
    return now, recorder.messages


def _stop_on_signals(event: threading.Event):
    """SIGINT/SIGTERM set ``event`` (the bag is then closed properly); returns the undo.

    The handler runs on the main thread between two bytecodes of whatever it was doing,
    e.g. inside ``event.wait`` holding the event's lock: ``event.set()`` there would wait
    for that lock forever. So the handler only queues the signal (``SimpleQueue.put`` is
    re-entrant, safe in a signal handler) and a "bag-signals" thread sets the event."""
    received: queue.SimpleQueue[int | None] = queue.SimpleQueue()

    def forward() -> None:
        while received.get() is not None:
            event.set()
    thread = threading.Thread(target=forward, name="bag-signals", daemon=True)
    thread.start()
    previous = {}
    for sig in (signal.SIGINT, signal.SIGTERM):
        previous[sig] = signal.signal(sig, lambda signum, _frame: received.put(signum))

    def undo() -> None:
        for sig, handler in previous.items():
            signal.signal(sig, handler)
        received.put(None)
        thread.join()
    return undo


# --- play -------------------------------------------------------------------------------------

@bag.command("play")
@click.argument("files", nargs=-1, required=True)
@click.option("-r", "--rate", default=1.0, type=click.FloatRange(min=0, min_open=True),
              help="Multiply the publish rate by this factor.")
@click.option("-s", "--start", default=0.0, type=click.FloatRange(min=0),
              help="Start this many seconds into the bag.")
@click.option("-u", "--duration", default=None, type=click.FloatRange(min=0),
              help="Play only this many seconds of the bag.")
@click.option("-l", "--loop", is_flag=True, help="Loop playback.")
@click.option("--clock", is_flag=True, help="Publish the bag time on /clock.")
@click.option("--hz", default=100.0, type=click.FloatRange(min=0, min_open=True),
              help="/clock frequency (default 100).")
@click.option("--topics", "topics", multiple=True,
              help="Play only these topics (repeat, or list them after --topics).")
@click.option("--pause", is_flag=True, help="Start paused.")
@click.option("-d", "--delay", default=0.2, type=click.FloatRange(min=0),
              help="Sleep this long after advertising (default 0.2 s).")
@click.option("-i", "--immediate", is_flag=True, help="Publish everything at once.")
@click.option("-q", "--quiet", is_flag=True, help="No progress line.")
@click.option("--wait-for-subscribers", is_flag=True,
              help="Start only once every topic has a subscriber.")
@click.option("--queue", "queue_size", default=100, type=click.IntRange(min=0),
              help="Outgoing queue size per topic (default 100).")
def play(files: tuple[str, ...], rate: float, start: float, duration: float | None,
         loop: bool, clock: bool, hz: float, topics: tuple[str, ...], pause: bool,
         delay: float, immediate: bool, quiet: bool, wait_for_subscribers: bool,
         queue_size: int) -> None:
    """Publish the messages of bags with their recorded timing (as rosbag play).

    On a terminal: space pauses and resumes, s publishes one message while paused."""
    from orchestra.bag.play import Player, PlayOptions
    from orchestra.node.tool import master_uri, require_master
    files, extra = _split_topics(files, topics)
    opts = PlayOptions(rate=rate, start=start, duration=duration, loop=loop, clock=clock,
                       hz=hz, topics=extra or None, pause=pause, delay=delay,
                       immediate=immediate, queue_size=queue_size,
                       wait_for_subscribers=wait_for_subscribers)
    from orchestra.bag.reader import BagReader
    readers = []
    try:
        for path in files:
            with bag_errors(path):
                readers.append(BagReader(path))
    except BaseException:
        for reader in readers:
            reader.close()
        raise
    player = Player(readers, opts)
    try:
        require_master(master_uri())
    except BaseException:
        player.close()
        raise
    import orchestra.node as rospy
    rospy.init_node("play", argv=[], anonymous=True, disable_signals=True,
                    disable_rosout=True, disable_rostime=True)
    stop = _stop_on_signals(player.stopped)
    worker = threading.Thread(target=player.run, name="bag-play", daemon=True)
    try:
        # the terminal is in cbreak mode before anything is advertised: a key pressed as
        # soon as a subscriber is connected is not lost
        with _keyboard(player) as keys:
            player.advertise()
            worker.start()
            while worker.is_alive():
                keys()
                if not quiet and sys.stdout.isatty():
                    _play_progress(player)
                worker.join(0.05)
    finally:
        player.stop()
        if worker.ident is not None:
            worker.join(2.0)
        stop()
        player.close()
        if not quiet and sys.stdout.isatty():
            click.echo("\nDone.")
        from orchestra.node.tool import stop_cli_node
        stop_cli_node("bag play done")
    if player.error is not None:
        raise BagError(f"damaged bag: {player.error}; `orchestra bag reindex` may help")


def _split_topics(files: tuple[str, ...], topics: tuple[str, ...]
                  ) -> tuple[tuple[str, ...], list[str]]:
    """rosbag's ``--topics A B C`` takes the words after it: here they arrive as files;
    a word that starts with '/', is no file and does not end in .bag is a topic."""
    bags = tuple(f for f in files
                 if not f.startswith("/") or f.endswith(".bag") or os.path.exists(f))
    names = list(topics) + [f for f in files if f not in bags]
    if not bags:
        raise click.UsageError("give at least one bag file")
    return bags, names


def _play_progress(player) -> None:
    st = player.state
    label = "[PAUSED ]" if st.paused else "[RUNNING]"
    elapsed = max(0, st.bag_time - st.first) / 1e9 if st.bag_time else 0.0
    total = (st.last - st.first) / 1e9
    click.echo(f"\r {label}  Bag Time: {st.bag_time / 1e9:13.6f}   Duration: "
               f"{elapsed:.6f} / {total:.6f}               ", nl=False)


@contextlib.contextmanager
def _keyboard(player):
    """Space toggles pause, s steps; only when stdin is a terminal (cbreak, no echo)."""
    if not sys.stdin.isatty():
        yield lambda: None
        return
    import termios
    import tty
    fd = sys.stdin.fileno()
    saved = termios.tcgetattr(fd)
    tty.setcbreak(fd, termios.TCSANOW)  # keep keys already typed

    def poll() -> None:
        while select.select([fd], [], [], 0)[0]:
            ch = os.read(fd, 1)
            if ch == b" ":
                player.state.toggle_pause()
            elif ch in (b"s", b"S"):
                player.state.request_step()
    try:
        yield poll
    finally:
        termios.tcsetattr(fd, termios.TCSADRAIN, saved)
