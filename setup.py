"""Ship the bundled demo packages (repo ``packages/``) with non-editable installs.

They are catkin packages, not Python packages, so they go in as data files under
``<prefix>/share/orchestra/packages``; orchestra's package index looks there when the
repository's own ``packages/`` directory is not beside the installed code. Everything else is
declared in pyproject.toml.
"""
import os

from setuptools import setup


def bundled_packages() -> list[tuple[str, list[str]]]:
    groups: dict[str, list[str]] = {}
    for root, dirs, files in os.walk("packages"):
        dirs[:] = sorted(d for d in dirs if d != "__pycache__")
        keep = [os.path.join(root, f) for f in sorted(files) if not f.endswith(".pyc")]
        if keep:
            groups.setdefault(os.path.join("share", "orchestra", root), []).extend(keep)
    return sorted(groups.items())


setup(data_files=bundled_packages())
