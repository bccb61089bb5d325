"""``import <pkg>.msg`` / ``<pkg>.srv`` for every package with definitions, no build step.

genpy-generated code gives each message package a Python package with ``msg`` and ``srv``
submodules. Here they are made on import, from ``orchestra.node.msg``'s classes:

- ``MessageModuleFinder`` (first on ``sys.meta_path``) answers ``<pkg>.msg`` and
  ``<pkg>.srv`` whenever ``pkg`` has definitions (rosbags' standard store, orchestra's bundled
  definitions, ``msg/``/``srv/``/``action/`` of a package on the package path). It goes first
  so that with the layer active every message class comes from one class system, even when
  some genpy-generated package happens to be importable too.
- ``PackageModuleFinder`` (last) answers a top-level ``<pkg>`` that nothing else found: a
  package module whose ``__path__`` is the package's ``src/<pkg>`` (catkin_python_setup's
  layout) when it has one, so ``from my_pkg.utils import x`` keeps working, and whose
  ``__init__.py`` there is run. ``import pkg.msg`` of a package that does not exist fails
  with a ModuleNotFoundError that says where it looked (any other missing module keeps
  Python's own error, so ``importlib.util.find_spec`` probes still get None).

Classes are built on first attribute access (PEP 562 ``__getattr__``): importing
``std_msgs.msg`` builds nothing, ``from std_msgs.msg import String`` builds String and its
dependencies only. ``from pkg.msg import *`` builds every type of the package.
"""
from __future__ import annotations

import importlib.abc
import importlib.machinery
import os
import sys
import threading
import types
from collections.abc import Sequence
from typing import Any

KINDS = ("msg", "srv")
#: modules Python itself looks for at start-up: never ROS packages, and answering them would
#: load orchestra in every process that merely has the layer on its path
_STARTUP_PROBES = frozenset({"usercustomize", "sitecustomize"})
_busy = threading.local()


def _reentrant() -> bool:
    """True while our finders cannot answer: one of them is already working in this thread
    (the imports it does itself are not ours), or some orchestra module is half-imported (a
    node importing orchestra.node, whose imports probe optional modules such as copy.py's
    ``org``): answering would use that half-made module."""
    if getattr(_busy, "depth", 0) > 0:
        return True
    for name, module in list(sys.modules.items()):
        if name.startswith("orchestra.") or name == "orchestra":
            spec = getattr(module, "__spec__", None)
            if spec is not None and getattr(spec, "_initializing", False):
                return True
    return False


class _Working:
    def __enter__(self) -> None:
        _busy.depth = getattr(_busy, "depth", 0) + 1

    def __exit__(self, *exc: object) -> None:
        _busy.depth -= 1


class DefinitionImportError(ImportError):
    """A definition that cannot be loaded: its message is ``file:line: what is wrong``."""


def _definitions():
    from orchestra.node import msgdefs
    return msgdefs


def _load_class(pkg: str, kind: str, name: str) -> Any:
    """The class for ``pkg/name``, or None when there is no such definition."""
    from orchestra.node import msg
    from orchestra.node.msgspec import MsgSpecError

    type_name = f"{pkg}/{name}"
    try:
        if kind == "msg":
            return msg.get_message_class(type_name)
        return msg.get_service_class(type_name)
    except msg.MessageNotFound:
        return None
    except MsgSpecError as exc:   # a broken definition, located at its file:line
        raise DefinitionImportError(str(exc), name=f"{pkg}.{kind}") from None


def _make_getattr(module: types.ModuleType, pkg: str, kind: str):
    def __getattr__(attr: str) -> Any:
        if attr == "__all__":
            names = _definitions().package_types(pkg, kind)
            if kind == "srv":   # genpy's srv modules also export <Srv>Request/<Srv>Response
                names = sorted(names + [n + s for n in names for s in ("Request", "Response")])
            setattr(module, "__all__", names)  # noqa: B010 - a module attribute
            return names
        if attr.startswith("__") or not attr[:1].isalpha():
            raise AttributeError(f"module {module.__name__!r} has no attribute {attr!r}")
        try:
            cls = _load_class(pkg, kind, attr)
        except DefinitionImportError as exc:
            # the user's definition is at fault: show its file:line, not our frames
            raise exc.with_traceback(None) from None
        if cls is None:
            raise AttributeError(f"module {module.__name__!r} has no attribute {attr!r} "
                                 f"(no {kind} definition {pkg}/{attr})")
        if kind == "srv":
            # genpy also puts <Srv>Request / <Srv>Response in the srv module
            setattr(module, f"{attr}Request", cls._request_class)
            setattr(module, f"{attr}Response", cls._response_class)
        setattr(module, attr, cls)
        return cls
    return __getattr__


def _srv_part(attr: str) -> tuple[str, str] | None:
    """``("AddTwoInts", "Request")`` for ``AddTwoIntsRequest``."""
    for suffix in ("Request", "Response"):
        if attr.endswith(suffix) and len(attr) > len(suffix):
            return attr[: -len(suffix)], suffix
    return None


class _MessageModuleLoader(importlib.abc.Loader):
    def __init__(self, pkg: str, kind: str):
        self.pkg, self.kind = pkg, kind

    def create_module(self, spec: importlib.machinery.ModuleSpec) -> types.ModuleType | None:
        return None

    def exec_module(self, module: types.ModuleType) -> None:
        pkg, kind = self.pkg, self.kind
        getattr_ = _make_getattr(module, pkg, kind)
        if kind == "srv":
            plain = getattr_

            def getattr_(attr: str) -> Any:   # noqa: F811 - AddTwoIntsRequest etc.
                try:
                    return plain(attr)
                except AttributeError:
                    part = _srv_part(attr)
                    if part is None:
                        raise
                    service = plain(part[0])
                    return getattr(service, f"_{part[1].lower()}_class")
        setattr(module, "__getattr__", getattr_)  # noqa: B010 - PEP 562 module hook

        def dir_() -> list[str]:   # dir(pkg.msg) lists the types, as a generated module does
            return sorted(set(module.__dict__) | set(getattr_("__all__")))
        setattr(module, "__dir__", dir_)  # noqa: B010 - PEP 562 module hook
        module.__doc__ = f"{kind} classes of package {pkg} (orchestra's ROS 1 layer)"


class MessageModuleFinder(importlib.abc.MetaPathFinder):
    """``<pkg>.msg`` and ``<pkg>.srv`` for packages with definitions."""

    def find_spec(self, fullname: str, path: Sequence[str] | None = None,
                  target: types.ModuleType | None = None) -> importlib.machinery.ModuleSpec | None:
        pkg, dot, kind = fullname.rpartition(".")
        if not dot or kind not in KINDS or "." in pkg or _reentrant():
            return None
        with _Working():
            if not _definitions().has_definitions(pkg):
                return None
        return importlib.machinery.ModuleSpec(fullname, _MessageModuleLoader(pkg, kind),
                                              origin=f"orchestra ROS 1 layer: {pkg}/{kind}")


class _PackageLoader(importlib.abc.Loader):
    def __init__(self, init_file: str | None):
        self.init_file = init_file

    def create_module(self, spec: importlib.machinery.ModuleSpec) -> types.ModuleType | None:
        return None

    def exec_module(self, module: types.ModuleType) -> None:
        if self.init_file is None:
            return
        with open(self.init_file, "rb") as fh:
            code = compile(fh.read(), self.init_file, "exec")
        exec(code, module.__dict__)  # noqa: S102 - the package's own __init__.py, as import would


def python_source_dir(pkg: str, directory: str) -> str | None:
    """``<package>/src/<pkg>`` when the package has Python code there (catkin_python_setup)."""
    candidate = os.path.join(directory, "src", pkg)
    return candidate if os.path.isdir(candidate) else None


def _importing_definitions_of(pkg: str) -> bool:
    """Whether this lookup of ``pkg`` is the first step of importing ``pkg.msg``/``pkg.srv``.

    Python imports a parent package before the submodule, so the finder asked for ``pkg``
    cannot see the dotted name; the import system's own frames above it still hold it.
    Only a failing lookup pays for this walk."""
    wanted = {f"{pkg}.{kind}" for kind in KINDS}
    frame: types.FrameType | None = sys._getframe(1)
    for _ in range(64):
        if frame is None:
            return False
        if frame.f_code.co_name == "_find_and_load_unlocked" and \
                frame.f_locals.get("name") in wanted:
            return True
        frame = frame.f_back
    return False


class PackageModuleFinder(importlib.abc.MetaPathFinder):
    """A top-level package module for a ROS package nothing else could import."""

    def find_spec(self, fullname: str, path: Sequence[str] | None = None,
                  target: types.ModuleType | None = None) -> importlib.machinery.ModuleSpec | None:
        if path is not None or "." in fullname or fullname in _STARTUP_PROBES or _reentrant():
            return None
        with _Working():
            try:
                return self._find(fullname)
            except ModuleNotFoundError as exc:
                raise exc.with_traceback(None) from None

    @staticmethod
    def _find(fullname: str) -> importlib.machinery.ModuleSpec | None:
        defs = _definitions()
        directory = defs.package_dir(fullname)
        source = python_source_dir(fullname, directory) if directory else None
        if source is None and not defs.has_definitions(fullname):
            if _importing_definitions_of(fullname):
                # `import pkg.msg` / `from pkg.srv import X`: say where we looked
                raise ModuleNotFoundError(
                    f"No module named '{fullname}': no ROS package {fullname} with msg/, "
                    f"srv/ or action/ definitions (looked in {defs.where_searched()})",
                    name=fullname)
            return None
        init = os.path.join(source, "__init__.py") if source else None
        init = init if init and os.path.isfile(init) else None
        spec = importlib.machinery.ModuleSpec(
            fullname, _PackageLoader(init), origin=init or f"orchestra ROS 1 layer: {fullname}",
            is_package=True)
        spec.submodule_search_locations = [source] if source else []
        if init:
            spec.has_location = True
        return spec


_FRONT = MessageModuleFinder()
_BACK = PackageModuleFinder()


def install(meta_path: list | None = None) -> None:
    """Put both finders on ``sys.meta_path`` (idempotent)."""
    meta_path = sys.meta_path if meta_path is None else meta_path
    if _FRONT not in meta_path:
        meta_path.insert(0, _FRONT)
    if _BACK not in meta_path:
        meta_path.append(_BACK)


def uninstall(meta_path: list | None = None) -> None:
    meta_path = sys.meta_path if meta_path is None else meta_path
    for finder in (_FRONT, _BACK):
        while finder in meta_path:
            meta_path.remove(finder)
