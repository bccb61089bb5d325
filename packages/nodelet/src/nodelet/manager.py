"""The nodelet manager's book-keeping: which nodelet runs under which name.

Kept free of any service plumbing so loading, name collisions and unloading are tested in
one process; ``main`` wires it to the ``~load_nodelet``/``~unload_nodelet``/``~list``
services.
"""
from __future__ import annotations

import logging
import socket
import threading
from collections.abc import Callable
from urllib.parse import urlparse

from nodelet import names
from nodelet.base import Nodelet
from nodelet.plugins import PluginError, load_plugin

log = logging.getLogger("nodelet.manager")


def is_user_error(exc: BaseException) -> bool:
    """Configuration mistakes (missing/bad params, bad files) are reported as one line;
    anything else is a plugin bug and deserves its traceback."""
    from orchestra.errors import OrchestraError
    return isinstance(exc, (OrchestraError, RuntimeError, ValueError, KeyError, OSError))


def uri_alive(uri: str, timeout: float = 1.0) -> bool:
    """Does something still listen at a node's XML-RPC URI? A killed loader's port closes at
    once, so a refused connection is a reliable death notice (no bond messages needed)."""
    parsed = urlparse(uri)
    if not parsed.hostname or not parsed.port:
        return True  # nothing we can check: assume alive rather than unload wrongly
    try:
        with socket.create_connection((parsed.hostname, parsed.port), timeout=timeout):
            return True
    except ConnectionRefusedError:
        return False
    except OSError:
        return True  # timeouts and routing trouble are not proof of death


class LoadError(Exception):
    """Why a load request was refused; the manager stays up, the loader reports it."""


class Manager:
    def __init__(self) -> None:
        self._nodelets: dict[str, Nodelet] = {}
        self._bonds: dict[str, str] = {}
        self._lock = threading.Lock()

    def load(self, name: str, type_name: str, remaps: dict[str, str],
             my_argv: list[str], bond: str = "") -> Nodelet:
        """Instantiate ``type_name`` as ``name`` and run its ``on_init``; raise LoadError.

        ``bond`` identifies the loader (its node URI). A request for a loaded name from a
        DIFFERENT loader replaces the old nodelet: one node per name is the graph's rule (the
        master shuts the older node of a name down), so the old loader is gone, typically
        killed and respawned, and its nodelet must not block the new one.
        """
        name = names.canonicalize(name)
        with self._lock:
            stale = (name in self._nodelets and self._nodelets[name] is not None and bond
                     and self._bonds.get(name) not in ("", bond))
        if stale:
            log.warning("nodelet %s is requested by a new loader: replacing the old one", name)
            self.unload(name)
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
            self._bonds[name] = bond
        log.info("loaded nodelet %s (%s)", name, type_name)
        return instance

    def unload(self, name: str) -> bool:
        name = names.canonicalize(name)
        with self._lock:
            instance = self._nodelets.pop(name, None)
            self._bonds.pop(name, None)
        if instance is None:
            return False
        instance.shutdown()
        log.info("unloaded nodelet %s", name)
        return True

    def list(self) -> list[str]:
        with self._lock:
            return sorted(n for n, inst in self._nodelets.items() if inst is not None)

    def bonds(self) -> dict[str, str]:
        """Loaded nodelet name -> its loader's bond (URI), for the liveness watchdog."""
        with self._lock:
            return {n: b for n, b in self._bonds.items() if b}

    def unload_orphans(self, alive: Callable[[str], bool]) -> list[str]:
        """Unload every nodelet whose loader is no longer ``alive`` (ROS's broken bond)."""
        gone = [name for name, bond in self.bonds().items() if not alive(bond)]
        for name in gone:
            log.warning("the loader of nodelet %s is gone: unloading it", name)
            self.unload(name)
        return gone

    def unload_all(self) -> None:
        for name in self.list():
            self.unload(name)
