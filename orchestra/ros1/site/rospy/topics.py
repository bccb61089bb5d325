"""rospy.topics: Publisher and Subscriber with rospy's signatures over orchestra's.

The argument lists differ from orchestra.node's classes: rospy's third positional argument
of ``Publisher`` is ``subscriber_listener`` (orchestra's is ``queue_size``), and rospy's
``queue_size`` defaults to None (no bound) for both. And rospy lets a script create its
topics before ``init_node`` (the tutorials' talker does): such a topic is registered when
the node starts (``start_deferred``, called by ``rospy.init_node``); publishing before then
is rospy's error.
"""
from __future__ import annotations

import threading
from collections.abc import Callable
from typing import Any

from orchestra.node import runtime as _runtime
from orchestra.node import topics as _topics
from orchestra.node.exceptions import ROSException
from orchestra.node.msg import Message

__all__ = ["Message", "Publisher", "SubscribeListener", "Subscriber"]


class SubscribeListener:
    """Base for ``Publisher(..., subscriber_listener=...)``: override to be told when a
    subscriber connects (``peer_publish`` sends to that subscriber only) or leaves."""

    def peer_subscribe(self, topic_name: str, topic_publish: Callable[[Any], None],
                       peer_publish: Callable[[Any], None]) -> None:
        pass

    def peer_unsubscribe(self, topic_name: str, num_peers: int) -> None:
        pass


_deferred: list[Callable[[], None]] = []
_deferred_lock = threading.Lock()


def _start_or_defer(topic: Any, name: str, data_class: Any, start: Callable[[], None]) -> None:
    with _deferred_lock:
        if not _runtime.is_initialized():
            if not (isinstance(data_class, type) and issubclass(data_class, Message)):
                raise ValueError(f"{type(topic).__name__} needs a message class, "
                                 f"not {data_class!r}")
            topic.name = topic.resolved_name = name
            topic.data_class = data_class
            topic.type = data_class._type
            topic.md5sum = data_class._md5sum
            topic._impl = None
            topic._done = False
            _deferred.append(start)
            return
    start()


def start_deferred() -> None:
    """Register the topics created before ``init_node`` (called once the node runs)."""
    with _deferred_lock:
        pending = list(_deferred)
        _deferred.clear()
    for start in pending:
        start()


class Publisher(_topics.Publisher):
    """rospy.Publisher(name, data_class, subscriber_listener=None, tcp_nodelay=False,
    latch=False, headers=None, queue_size=None)."""

    def __init__(self, name: str, data_class: type[Message],
                 subscriber_listener: SubscribeListener | None = None,
                 tcp_nodelay: bool = False, latch: bool = False,
                 headers: dict | None = None, queue_size: int | None = None):
        def start() -> None:
            if not getattr(self, "_done", False):
                super(Publisher, self).__init__(name, data_class, queue_size=queue_size,
                                                latch=latch,
                                                subscriber_listener=subscriber_listener)
        _start_or_defer(self, name, data_class, start)

    def publish(self, *args: Any, **kwargs: Any) -> None:
        if self._impl is None:
            raise ROSException("ROS node has not been initialized yet. "
                               "Please call init_node() first")
        super().publish(*args, **kwargs)

    def get_num_connections(self) -> int:
        return 0 if self._impl is None else super().get_num_connections()

    def unregister(self) -> None:
        if self._impl is None:
            self._done = True
        else:
            super().unregister()


class Subscriber(_topics.Subscriber):
    """rospy.Subscriber(name, data_class, callback=None, callback_args=None, queue_size=None,
    buff_size=65536, tcp_nodelay=False)."""

    def __init__(self, name: str, data_class: type[Message], callback: Callable | None = None,
                 callback_args: Any = None, queue_size: int | None = None,
                 buff_size: int = 65536, tcp_nodelay: bool = False):
        self.callback, self.callback_args = callback, callback_args

        def start() -> None:
            if not getattr(self, "_done", False):
                super(Subscriber, self).__init__(name, data_class, callback, callback_args,
                                                 queue_size=queue_size)
        _start_or_defer(self, name, data_class, start)

    def get_num_connections(self) -> int:
        return 0 if self._impl is None else super().get_num_connections()

    def unregister(self) -> None:
        if self._impl is None:
            self._done = True
        else:
            super().unregister()
