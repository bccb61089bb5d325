"""Where message, service and action definitions come from, one type at a time.

Sources, in order:

1. the standard ROS 1 message packages, from rosbags' noetic type store. Importing that store
   module costs ~45 ms (it defines a dataclass per type), too much for a node that needs one
   message, so its definitions are written once to a small JSON cache (next to the package
   index cache, keyed by the store file's size and mtime) and read from there afterwards;
2. the few standard definitions rosbags lacks (``definitions/``: std_srvs, tf2_msgs, ...);
3. ``msg/*.msg``, ``srv/*.srv`` and ``action/*.action`` of the package found on the package
   path (``orchestra.packages``): a user's own types, with no build step. An ``.action``
   file gives the seven message types genaction would generate.

Nothing here parses: it hands out definition text with the file (and line) it came from,
so parse errors can name ``file:line``.
"""
from __future__ import annotations

import json
import logging
import os
import sys
import threading
from dataclasses import dataclass

from orchestra import rosdirs
from orchestra.node import msgspec

log = logging.getLogger(__name__)

DEFINITIONS = os.path.join(os.path.dirname(os.path.abspath(__file__)), "definitions")
KINDS = ("msg", "srv", "action")
#: the rosbags store module whose definitions are cached (found on sys.path, not imported)
_STORE_MODULE = os.path.join("rosbags", "typesys", "stores", "ros1_noetic.py")
#: ROS 2 types rosbags keeps in its ROS 1 store for its own use; not ROS 1 message packages
_NOT_ROS1 = ("builtin_interfaces",)
#: suffixes of the types generated from ``<Name>.action``, longest first (``FooActionGoal``
#: is Foo's ActionGoal before it is FooAction's Goal)
_ACTION_SUFFIXES = ("ActionFeedback", "ActionResult", "ActionGoal", "Action", "Feedback",
                    "Result", "Goal")


@dataclass(frozen=True)
class Definition:
    """The text of one type's definition and where it was read."""

    type: str
    kind: str           # "msg" or "srv"
    text: str
    path: str = ""      # the file ("" for rosbags' store)
    first_line: int = 1  # file line of the text's first line (parts of .srv/.action files)

    @property
    def origin(self) -> str:
        return self.path or "rosbags' standard ROS 1 (noetic) type store"


# --- 1. the standard store ----------------------------------------------------------------

_lock = threading.Lock()
_standard: dict[str, str] | None = None


def _store_file() -> str | None:
    for entry in sys.path:
        candidate = os.path.join(entry or ".", _STORE_MODULE)
        if os.path.isfile(candidate):
            return candidate
    return None


def _cache_path(store_file: str) -> str | None:
    # rosdirs, not orchestra.packages: this runs in every node's init_node (/rosout's Log),
    # and importing the package index there cost a node ~10 ms (bench_rospy_layer.py)
    directory = rosdirs.cache_dir()
    if directory is None:
        return None
    st = os.stat(store_file)
    return os.path.join(directory, f"ros1-msgdefs-{st.st_size}-{st.st_mtime_ns}.json")


def _read_store() -> dict[str, str]:
    """Every standard type's own definition text, from rosbags (the slow path); none when
    this interpreter has no rosbags (a node's Python that is not orchestra's)."""
    try:
        from rosbags.typesys import Stores, get_typestore
    except ImportError:
        log.debug("rosbags is not importable: no standard message definitions")
        return {}

    store = get_typestore(Stores.ROS1_NOETIC)
    texts: dict[str, str] = {}
    for key in store.fielddefs:
        pkg, _, name = key.split("/")
        if pkg in _NOT_ROS1:
            continue
        full, _md5 = store.generate_msgdef(key)
        texts[f"{pkg}/{name}"] = full.split(msgspec.SEPARATOR, 1)[0].rstrip("\n") + "\n"
    return texts


def _load_cache(path: str) -> dict[str, str] | None:
    try:
        with open(path, encoding="utf-8") as fh:
            data = json.load(fh)
    except (OSError, ValueError):
        return None
    return data if isinstance(data, dict) else None


def _save_cache(path: str, texts: dict[str, str]) -> None:
    tmp = f"{path}.{os.getpid()}.tmp"
    try:
        os.makedirs(os.path.dirname(path), exist_ok=True)
        with open(tmp, "w", encoding="utf-8") as fh:
            json.dump(texts, fh)
        os.replace(tmp, path)   # atomic: a concurrent reader sees the old or the new file
    except OSError as exc:
        log.debug("cannot write the message definition cache %s: %s", path, exc)


def standard_texts() -> dict[str, str]:
    """``pkg/Name`` -> definition text of every standard message (cached per process)."""
    global _standard
    with _lock:
        if _standard is None:
            store_file = _store_file()
            path = _cache_path(store_file) if store_file else None
            texts = _load_cache(path) if path else None
            if texts is None:
                texts = _read_store()
                if path:
                    _save_cache(path, texts)
            _standard = texts
        return _standard


# --- 2./3. files ---------------------------------------------------------------------------

def package_dir(pkg: str) -> str | None:
    """The package's directory on the package path, or None."""
    from orchestra.errors import OrchestraError
    from orchestra.packages import find_package

    try:
        return find_package(pkg)
    except OrchestraError:
        return None


def _read(path: str) -> str:
    with open(path, encoding="utf-8") as fh:
        return fh.read()


def _file(pkg: str, kind: str, name: str) -> str | None:
    bundled = os.path.join(DEFINITIONS, pkg, kind, f"{name}.{kind}")
    if os.path.isfile(bundled):
        return bundled
    directory = package_dir(pkg)
    if directory is None:
        return None
    path = os.path.join(directory, kind, f"{name}.{kind}")
    return path if os.path.isfile(path) else None


def _from_action(pkg: str, name: str) -> Definition | None:
    for suffix in _ACTION_SUFFIXES:
        if name.endswith(suffix) and len(name) > len(suffix):
            path = _file(pkg, "action", name[: -len(suffix)])
            if path is not None:
                texts = msgspec.action_message_texts(_read(path), f"{pkg}/{name[:-len(suffix)]}",
                                                     path)
                text, first_line = texts[f"{pkg}/{name}"]
                return Definition(f"{pkg}/{name}", "msg", text, path, first_line)
    return None


def find_message(msg_type: str) -> Definition | None:
    """The definition of message ``pkg/Name``, or None when no source has it."""
    pkg, _, name = msg_type.partition("/")
    text = standard_texts().get(msg_type)
    if text is not None:
        return Definition(msg_type, "msg", text)
    path = _file(pkg, "msg", name)
    if path is not None:
        return Definition(msg_type, "msg", _read(path), path)
    return _from_action(pkg, name)


def find_service(srv_type: str) -> Definition | None:
    """The definition of service ``pkg/Name`` (the whole ``.srv`` text), or None."""
    pkg, _, name = srv_type.partition("/")
    path = _file(pkg, "srv", name)
    return Definition(srv_type, "srv", _read(path), path) if path is not None else None


def find_raw(type_name: str, kind: str) -> Definition | None:
    """A definition as written in its file when there is one (comments kept, what ``rosmsg
    show -r`` prints), else what ``find_message``/``find_service`` have."""
    pkg, _, name = type_name.partition("/")
    directory = package_dir(pkg)
    if directory is not None:
        path = os.path.join(directory, kind, f"{name}.{kind}")
        if os.path.isfile(path):
            return Definition(type_name, kind, _read(path), path)
    return find_message(type_name) if kind == "msg" else find_service(type_name)


# --- listings -----------------------------------------------------------------------------

def _names_in(directory: str | None, kind: str) -> list[str]:
    if directory is None:
        return []
    sub = os.path.join(directory, kind)
    try:
        entries = os.listdir(sub)
    except OSError:
        return []
    return [e[: -len(kind) - 1] for e in entries if e.endswith("." + kind)]


def package_types(pkg: str, kind: str) -> list[str]:
    """Sorted type names (``Name``, not ``pkg/Name``) of ``pkg``'s messages or services;
    an action's seven generated messages count as messages."""
    names: set[str] = set()
    if kind == "msg":
        names.update(t.split("/")[1] for t in standard_texts() if t.split("/")[0] == pkg)
    for directory in (os.path.join(DEFINITIONS, pkg), package_dir(pkg)):
        names.update(_names_in(directory, kind))
        if kind == "msg":
            for action in _names_in(directory, "action"):
                names.update(action + s for s in _ACTION_SUFFIXES)
    return sorted(names)


def packages(kind: str) -> list[str]:
    """Sorted names of every package with definitions of ``kind`` (msg: .action counts)."""
    from orchestra.packages import get_index

    found: set[str] = set()
    if kind == "msg":
        found.update(t.split("/")[0] for t in standard_texts())
    kinds = (kind, "action") if kind == "msg" else (kind,)
    for pkg in os.listdir(DEFINITIONS):
        if any(os.path.isdir(os.path.join(DEFINITIONS, pkg, k)) for k in kinds):
            found.add(pkg)
    for pkg, directory in get_index().packages.items():
        if any(_names_in(directory, k) for k in kinds):
            found.add(pkg)
    return sorted(found)


def has_definitions(pkg: str) -> bool:
    """Whether ``pkg`` has any message, service or action definition in any source."""
    if any(t.split("/")[0] == pkg for t in standard_texts()):
        return True
    if os.path.isdir(os.path.join(DEFINITIONS, pkg)):
        return True
    return any(_names_in(package_dir(pkg), k) for k in KINDS)


def where_searched() -> str:
    """The sources looked in, for a "not found" message."""
    from orchestra.packages.discovery import search_roots

    roots = ", ".join(r.path for r in search_roots()) or "(none)"
    return ("rosbags' standard ROS 1 store, orchestra's bundled definitions "
            f"({DEFINITIONS}) and the msg/, srv/, action/ directories of packages under "
            f"{roots}")
