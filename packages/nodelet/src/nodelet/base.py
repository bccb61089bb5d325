"""The ``Nodelet`` base class: a node that runs inside a manager process.

A nodelet gets its identity (name, remappings, argv) from whoever loads it, not from the
process, so every topic/param/service name it uses goes through ``resolve`` against that
identity and reaches ``orchestra.node`` as a global name. Everything it creates is
remembered so ``shutdown`` (unload) removes exactly this nodelet's traffic and timers and
leaves the manager and its other nodelets running.
"""
from __future__ import annotations

import logging
import threading
from collections.abc import Callable
from typing import Any

from nodelet import names
from nodelet.local import BUS, NodeletPublisher

_MISSING = object()


def from_other_process(msg: Any, own_node: str) -> bool:
    """False for a TCPROS message this very process published (orchestra.node, like rospy,
    delivers a node's own publications to its subscribers): the local bus delivered it
    already, and a nodelet must see each message once."""
    header = getattr(msg, "_connection_header", None) or {}
    return header.get("callerid") != own_node


class Timer:
    """Calls ``callback(now_seconds)`` every ``period`` seconds on its own thread until stopped."""

    def __init__(self, period: float, callback: Callable[[float], None], name: str):
        self.period = period
        self.callback = callback
        self._stop = threading.Event()
        self._log = NodeletLog(name)
        self._thread = threading.Thread(target=self._run, name=f"timer:{name}", daemon=True)
        self._thread.start()

    def _run(self) -> None:
        import time
        next_time = time.monotonic()
        while not self._stop.is_set():
            next_time += self.period
            try:
                self.callback(time.time())
            except Exception:  # a faulty callback must not kill the manager's other nodelets
                self._log.exception("timer callback failed")
            delay = next_time - time.monotonic()
            if delay < 0:  # fell behind: do not try to catch up in a burst
                next_time = time.monotonic()
                delay = 0
            self._stop.wait(delay)

    def shutdown(self) -> None:
        self._stop.set()


class NodeletLog:
    """``info/warning/error/exception`` that reach /rosout through the hosting process's node
    (prefixed with the nodelet's name, since every nodelet shares that node), or plain
    ``logging`` when no node runs (unit tests)."""

    def __init__(self, name: str):
        self.name = name
        self._logger = logging.getLogger(name)

    def _emit(self, level: str, msg: str, args: tuple) -> None:
        try:
            from orchestra import node
            node.get_name()
        except Exception:
            getattr(self._logger, {"logerr": "error", "logwarn": "warning"}.get(
                level, "info" if level == "loginfo" else "debug"))(msg, *args)
            return
        getattr(node, level)("[%s] " + msg, self.name, *args)

    def debug(self, msg: str, *args: Any) -> None:
        self._emit("logdebug", msg, args)

    def info(self, msg: str, *args: Any) -> None:
        self._emit("loginfo", msg, args)

    def warning(self, msg: str, *args: Any) -> None:
        self._emit("logwarn", msg, args)

    def error(self, msg: str, *args: Any) -> None:
        self._emit("logerr", msg, args)

    def exception(self, msg: str, *args: Any) -> None:
        import traceback
        self._emit("logerr", msg + "\n%s", args + (traceback.format_exc(),))


class Nodelet:
    """Subclass and override ``on_init`` (roscpp's ``onInit``): create publishers,
    subscribers, services and timers there through the helpers below."""

    def __init__(self, name: str, remaps: dict[str, str] | None = None,
                 my_argv: list[str] | None = None):
        self.name = names.canonicalize(name)
        self.namespace = names.namespace_of(self.name)
        self.remaps = dict(remaps or {})
        self.my_argv = list(my_argv or [])
        self.log = NodeletLog(self.name)
        self._handles: list[Any] = []
        self._timers: list[Timer] = []
        self._lock = threading.Lock()
        self._shut_down = False

    # ---- to override -------------------------------------------------------------------
    def on_init(self) -> None:
        """Set the nodelet up; raising here makes the load fail (and the loader exit)."""

    def on_shutdown(self) -> None:
        """Release what ``on_init`` took beyond publishers/subscribers/services/timers."""

    # ---- names and params --------------------------------------------------------------
    def resolve(self, name: str) -> str:
        return names.resolve(name, self.name, self.remaps)

    def get_param(self, name: str, default: Any = _MISSING) -> Any:
        """A parameter by nodelet-relative name (``~x`` is the nodelet's private one)."""
        from orchestra import node
        resolved = names.resolve(name, self.name)
        if default is _MISSING:
            return node.get_param(resolved)
        return node.get_param(resolved, default)

    def get_private_param(self, name: str, default: Any = _MISSING) -> Any:
        return self.get_param("~" + name, default)

    # ---- graph resources ---------------------------------------------------------------
    def _keep(self, handle: Any) -> Any:
        with self._lock:
            self._handles.append(handle)
        return handle

    def advertise(self, topic: str, msg_class: type, queue_size: int = 10,
                  latch: bool = False) -> Any:
        from orchestra import node
        resolved = self.resolve(topic)
        remote = node.Publisher(resolved, msg_class, queue_size=queue_size, latch=latch)
        return self._keep(NodeletPublisher(remote, resolved, latch))

    def subscribe(self, topic: str, msg_class: type, callback: Callable[[Any], None],
                  queue_size: int = 10) -> Any:
        from orchestra import node
        resolved = self.resolve(topic)
        # other nodelets of this process publish through the local bus, the rest over TCPROS
        self._keep(BUS.subscribe(resolved, msg_class._type, callback, queue_size))
        own = node.get_name()

        def remote(msg: Any) -> None:
            if from_other_process(msg, own):
                callback(msg)
        return self._keep(node.Subscriber(resolved, msg_class, remote, queue_size=queue_size))

    def advertise_service(self, name: str, srv_class: type,
                          handler: Callable[[Any], Any]) -> Any:
        from orchestra import node
        return self._keep(node.Service(self.resolve(name), srv_class, handler))

    def create_timer(self, period: float, callback: Callable[[float], None]) -> Timer:
        timer = Timer(period, callback, self.name)
        with self._lock:
            self._timers.append(timer)
        return timer

    # ---- lifecycle ---------------------------------------------------------------------
    def shutdown(self) -> None:
        """Stop timers first (they publish), then drop every registration. Idempotent."""
        with self._lock:
            if self._shut_down:
                return
            self._shut_down = True
            timers, handles = self._timers[:], self._handles[:]
        for timer in timers:
            timer.shutdown()
        try:
            self.on_shutdown()
        except Exception:
            self.log.exception("on_shutdown failed")
        for handle in reversed(handles):
            stop = getattr(handle, "unregister", None) or getattr(handle, "shutdown", None)
            if stop is not None:
                try:
                    stop()
                except Exception:
                    self.log.debug("unregistering %r failed", handle, exc_info=True)
