"""Shared fixtures: where ../shared is, and a clean environment for launch resolution."""
from __future__ import annotations

from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parent.parent
SHARED = REPO.parent / "shared"
COMPAT = SHARED / "compat"


def _plugin_installed() -> bool:
    """True when orchestra's pytest plugin comes in through its entry point already."""
    from importlib.metadata import entry_points

    return any(ep.value == "orchestra.app.pytest_plugin"
               for ep in entry_points(group="pytest11"))


# an installation older than the plugin (or none: PYTHONPATH only) still gets the fixture
pytest_plugins = [] if _plugin_installed() else ["orchestra.app.pytest_plugin"]


@pytest.fixture
def compat_dir() -> Path:
    if not COMPAT.is_dir():
        pytest.skip("../shared/compat is not beside the repository")
    return COMPAT


def _harness():
    """tests/node_fixtures/harness.py, imported the way the node test modules import it."""
    import sys

    path = str(Path(__file__).resolve().parent / "node_fixtures")
    if path not in sys.path:
        sys.path.insert(0, path)
    import harness

    return harness


@pytest.fixture
def master():
    """orchestra's master on a free loopback port (tests run beside others' on one machine)."""
    from orchestra.master import start_master

    handle = start_master(host="127.0.0.1", port=0)
    yield handle
    handle.shutdown()


@pytest.fixture(scope="module")
def package_path(tmp_path_factory) -> Path:
    """A package path holding the node-runtime test package (tests/node_fixtures/harness.py)."""
    return _harness().make_test_package(tmp_path_factory.mktemp("pkgs"))


@pytest.fixture
def nodes(master, package_path):
    """Real node processes of the test package, talking through ``master``."""
    group = _harness().Nodes(master.uri, package_path)
    yield group
    group.close()
