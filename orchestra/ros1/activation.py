"""When and how a process gets the ROS 1 layer: one environment variable, one directory.

A node started by orchestra gets ``SITE_DIR`` prepended to its ``PYTHONPATH``. Python then
runs ``site/sitecustomize.py`` at start-up, which decides (``decide``) from
``ORCHESTRA_ROS1``:

- ``auto`` (default): the layer only when the interpreter cannot import a real ``rospy``
  from anywhere else on its path, so a real ROS install is never shadowed;
- ``layer``: always the layer (even with ROS installed);
- ``real``: never the layer (the site directory removes itself from ``sys.path``).

This module imports nothing of orchestra: the supervisor uses it to build a node's
environment and ``sitecustomize`` uses it inside every node, before anything else loads.
"""
from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from importlib.machinery import PathFinder

ENV_VAR = "ORCHESTRA_ROS1"
MODES = ("auto", "layer", "real")
SITE_DIR = os.path.join(os.path.dirname(os.path.abspath(__file__)), "site")
#: the directory holding the ``orchestra`` package (for interpreters that lack orchestra)
SOURCE_ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def _same(a: str, b: str) -> bool:
    return os.path.normcase(os.path.abspath(a or ".")) == os.path.normcase(os.path.abspath(b))


def without_site(path: Sequence[str], site_dir: str = SITE_DIR) -> list[str]:
    """``path`` minus the layer's site directory."""
    return [p for p in path if not _same(p, site_dir)]


def real_rospy_available(path: Sequence[str], site_dir: str = SITE_DIR) -> bool:
    """Whether ``import rospy`` would find a rospy that is not the layer's."""
    return PathFinder.find_spec("rospy", without_site(path, site_dir)) is not None


def mode_of(environ: Mapping[str, str]) -> str:
    """The requested mode; an unknown value counts as ``auto`` (see ``bad_mode``)."""
    mode = environ.get(ENV_VAR, "auto").strip().lower() or "auto"
    return mode if mode in MODES else "auto"


def bad_mode(environ: Mapping[str, str]) -> str | None:
    """A one-line warning when ``ORCHESTRA_ROS1`` holds something other than a mode."""
    value = environ.get(ENV_VAR, "").strip().lower()
    if value and value not in MODES:
        return (f"orchestra: warning: {ENV_VAR}={environ[ENV_VAR]!r} is not one of "
                f"{', '.join(MODES)}; using auto")
    return None


def decide(environ: Mapping[str, str], path: Sequence[str], site_dir: str = SITE_DIR) -> bool:
    """True when this process should use the layer (see the module docstring)."""
    mode = mode_of(environ)
    if mode == "layer":
        return True
    if mode == "real":
        return False
    return not real_rospy_available(path, site_dir)


def layer_env(environ: Mapping[str, str]) -> dict[str, str]:
    """What to add to a node's environment so its Python may use the layer: ``SITE_DIR``
    first on ``PYTHONPATH`` (kept once; the rest of the caller's PYTHONPATH follows)."""
    current = [p for p in environ.get("PYTHONPATH", "").split(os.pathsep) if p]
    return {"PYTHONPATH": os.pathsep.join([SITE_DIR, *without_site(current)])}
