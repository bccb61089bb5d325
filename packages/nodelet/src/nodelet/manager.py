"""The nodelet manager's book-keeping: which nodelet runs under which name.

Kept free of any service plumbing so loading, name collisions and unloading are tested in
one process; ``main`` wires it to the ``~load_nodelet``/``~unload_nodelet``/``~list``
services.
"""
from __future__ import annotations

import logging
import threading

from nodelet import names
from nodelet.base import Nodelet
from nodelet.plugins import PluginError, load_plugin

log = logging.getLogger("nodelet.manager")


def is_user_error(exc: BaseException) -> bool:
    """Configuration mistakes (missing/bad params, bad files) are reported as one line;
    anything else is a plugin bug and deserves its traceback."""
    from orchestra.errors import OrchestraError
    return isinstance(exc, (OrchestraError, RuntimeError, ValueError, KeyError, OSError))


class LoadError(Exception):
    """Why a load request was refused; the manager stays up, the loader reports it."""


class Manager:
    def __init__(self) -> None:
        self._nodelets: dict[str, Nodelet] = {}
        self._lock = threading.Lock()

    def load(self, name: str, type_name: str, remaps: dict[str, str],
             my_argv: list[str]) -> Nodelet:
        """Instantiate ``type_name`` as ``name`` and run its ``on_init``; raise LoadError."""
        name = names.canonicalize(name)
        with self._lock:
            if name in self._nodelets:
                raise LoadError(f"a nodelet named '{name}' is already loaded")
            self._nodelets[name] = None  # reserve the name while on_init runs
        try:
            try:
                cls = load_plugin(type_name)
            except PluginError as exc:
                raise LoadError(str(exc)) from None
            if not issubclass(cls, Nodelet):
                raise LoadError(f"'{type_name}' is not a nodelet.Nodelet subclass")
            instance = cls(name, remaps, my_argv)
            try:
                instance.on_init()
            except Exception as exc:
                instance.shutdown()
                if not is_user_error(exc):  # a bug in the plugin: keep the traceback
                    log.exception("nodelet %s (%s) failed in on_init", name, type_name)
                raise LoadError(f"'{type_name}' failed to initialise: {exc}") from None
        except BaseException:
            with self._lock:
                self._nodelets.pop(name, None)
            raise
        with self._lock:
            self._nodelets[name] = instance
        log.info("loaded nodelet %s (%s)", name, type_name)
        return instance

    def unload(self, name: str) -> bool:
        name = names.canonicalize(name)
        with self._lock:
            instance = self._nodelets.pop(name, None)
        if instance is None:
            return False
        instance.shutdown()
        log.info("unloaded nodelet %s", name)
        return True

    def list(self) -> list[str]:
        with self._lock:
            return sorted(n for n, inst in self._nodelets.items() if inst is not None)

    def unload_all(self) -> None:
        for name in self.list():
            self.unload(name)
