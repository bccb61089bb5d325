"""The aggregation step of rosout: every /rosout message goes out again on /rosout_agg, then
into rosout.log.

Republishing comes first (as rosout does) so a slow or full disk never delays live
consumers such as rqt_console. The publish function and the log are passed in, which keeps
this testable without a master or sockets.
"""
from __future__ import annotations

from collections.abc import Callable
from typing import Any

from rosout_core.logfile import RosoutLog, format_line


class Aggregator:
    """Receives /rosout messages (one at a time: the subscription's callbacks never overlap)."""

    def __init__(self, publish: Callable[[Any], None], log: RosoutLog | None,
                 omit_topics: bool = False):
        self.publish = publish
        self.log = log
        self.omit_topics = omit_topics
        self.count = 0

    def on_message(self, msg: Any) -> None:
        self.count += 1
        self.publish(msg)
        if self.log is not None:
            self.log.write(format_line(msg, self.omit_topics))
