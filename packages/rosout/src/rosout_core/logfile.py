"""rosout.log: where it lives, what a line looks like, and how it rotates.

The line format is ROS 1 rosout's (noetic), because people grep these files and tools parse
them::

    1700000000.012345678 INFO /talker [talker.py:12(main)] [topics: /rosout, /chatter] hi

that is ``<stamp secs.nsecs> <LEVEL> <node> [<file>:<line>(<function>)] [topics: a, b] <msg>``,
the ``[topics: ...]`` part left out when the ``/rosout/omit_topics`` parameter is true. Each
start adds two empty lines and ``<now>  Node Startup``. Past ``max_bytes`` the file
is rotated ``rosout.log -> rosout.log.1 -> ... -> rosout.log.<max_backups>`` (the oldest
dropped), checked after each write, as rosout does.
"""
from __future__ import annotations

import logging
import os
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, BinaryIO

logger = logging.getLogger(__name__)

LOG_FILE_NAME = "rosout.log"
DEFAULT_MAX_BYTES = 100 * 1024 * 1024    # rosout's hard-coded 100 MB
DEFAULT_MAX_BACKUPS = 10                 # rosout.log.1 ... rosout.log.10

#: rosgraph_msgs/Log level constants -> the word rosout writes
LEVEL_NAMES = {1: "DEBUG", 2: "INFO", 4: "WARN", 8: "ERROR", 16: "FATAL"}


def format_stamp(secs: int, nsecs: int) -> str:
    """A ROS time as roscpp prints it: seconds, a dot, nanoseconds on nine digits."""
    return f"{int(secs)}.{int(nsecs):09d}"


def level_name(level: int) -> str:
    """The level word; an unknown level is written as its number rather than dropped."""
    return LEVEL_NAMES.get(int(level), str(int(level)))


def format_line(msg: Any, omit_topics: bool = False) -> str:
    """The rosout.log line (newline included) for a rosgraph_msgs/Log message."""
    stamp = msg.header.stamp
    parts = [format_stamp(stamp.secs, stamp.nsecs), level_name(msg.level), msg.name,
             f"[{msg.file}:{msg.line}({msg.function})]"]
    if not omit_topics:
        parts.append(f"[topics: {', '.join(msg.topics)}]")
    parts.append(msg.msg)
    return " ".join(parts) + "\n"


def startup_banner(secs: int, nsecs: int) -> str:
    """What rosout writes first into a new rosout.log."""
    return f"\n\n{format_stamp(secs, nsecs)}  Node Startup\n"


def log_argument(argv: Sequence[str]) -> str | None:
    """The value of the ``__log:=FILE`` word roslaunch (and orchestra) give every node."""
    for word in argv:
        if word.startswith("__log:="):
            return word[len("__log:="):] or None
    return None


def log_directory(argv: Sequence[str], environ: Mapping[str, str]) -> str:
    """The directory rosout.log goes in, by roscpp's rule.

    The directory of ``__log:=`` when given: under roslaunch/orchestra that is the run's
    directory ``<log root>/<run_id>``. Otherwise the log root itself: ``$ROS_LOG_DIR``, else
    ``$ROS_HOME/log``, else ``~/.ros/log`` (a bare ``rosrun rosout rosout`` knows no run id).
    """
    given = log_argument(argv)
    if given:
        return os.path.dirname(os.path.abspath(given))
    if environ.get("ROS_LOG_DIR"):
        return environ["ROS_LOG_DIR"]
    home = environ.get("ROS_HOME") or os.path.join(
        environ.get("HOME") or os.path.expanduser("~"), ".ros")
    return os.path.join(home, "log")


@dataclass(frozen=True)
class Rotation:
    """One rotation step: the backup to delete first (if any), then renames in order."""

    delete: str | None
    renames: tuple[tuple[str, str], ...]
    backups: int          # how many backups exist afterwards


def plan_rotation(path: str, backups: int, max_backups: int) -> Rotation:
    """How to rotate ``path`` when ``backups`` numbered copies exist (at most ``max_backups``).

    The renames run from the oldest down so nothing is overwritten before it was moved on;
    with ``max_backups`` 0 nothing is kept (the file is just started again).
    """
    delete = f"{path}.{max_backups}" if max_backups and backups >= max_backups else None
    after = min(max_backups, backups + 1)
    renames = tuple((path if i == 1 else f"{path}.{i - 1}", f"{path}.{i}")
                    for i in range(after, 0, -1))
    return Rotation(delete, renames, after)


@dataclass
class RosoutLog:
    """The open rosout.log: appended to, flushed after every line so the file is complete
    whenever someone reads it, rotated past ``max_bytes`` (0 = never).

    I/O errors are logged and do not stop the node: aggregation on /rosout_agg matters more
    than the file.
    """

    path: str
    max_bytes: int = DEFAULT_MAX_BYTES
    max_backups: int = DEFAULT_MAX_BACKUPS
    size: int = 0
    backups: int = 0
    _fh: BinaryIO | None = field(default=None, repr=False)

    def open(self, banner: str = "") -> None:
        """Open for appending: a respawned rosout (or a second run with the same run id)
        continues the file after its ``Node Startup`` banner instead of wiping what the
        previous instance wrote, which roscpp's rosout does."""
        os.makedirs(os.path.dirname(self.path) or ".", exist_ok=True)
        self._fh = open(self.path, "ab")
        self.size = self._fh.tell()
        if banner:
            self.write(banner)

    def write(self, text: str) -> None:
        if self._fh is None:
            return
        data = text.encode("utf-8", "replace")
        try:
            self._fh.write(data)
            self._fh.flush()
        except OSError as exc:
            logger.error("cannot write %s: %s", self.path, exc)
            return
        self.size += len(data)
        if self.max_bytes and self.size > self.max_bytes:
            self.rotate()

    def rotate(self) -> None:
        self.close()
        step = plan_rotation(self.path, self.backups, self.max_backups)
        _apply(step)
        self.backups = step.backups
        try:
            self._fh = open(self.path, "ab")
        except OSError as exc:
            logger.error("cannot reopen %s after rotation: %s", self.path, exc)
            self._fh = None
        self.size = 0

    def close(self) -> None:
        if self._fh is not None:
            try:
                self._fh.close()
            except OSError:
                pass
            self._fh = None


def _apply(step: Rotation) -> None:
    actions: Iterable[tuple[str, str | None]] = (
        [(step.delete, None)] if step.delete else []) + list(step.renames)
    for src, dst in actions:
        try:
            if dst is None:
                os.unlink(src)
            else:
                os.replace(src, dst)
        except FileNotFoundError:
            pass              # a backup that was never made, or removed by someone else
        except OSError as exc:
            logger.error("cannot rotate %s: %s", src, exc)
