"""The rospy-style API inside one node process: params, waiting, logging, shutdown hooks."""
from __future__ import annotations

import sys
import xmlrpc.client
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent / "node_fixtures"))
from harness import Nodes, make_test_package  # noqa: E402

from orchestra.master import start_master  # noqa: E402

pytestmark = pytest.mark.timeout(60)


@pytest.fixture
def nodes(tmp_path):
    handle = start_master(host="127.0.0.1", port=0)
    group = Nodes(handle.uri, make_test_package(tmp_path))
    yield group
    group.close()
    handle.shutdown()


def test_params_waits_logging_and_shutdown_hooks_behave_like_rospy(nodes):
    nodes.start("pub.py", "feed", "std_msgs/String", "data: fed").ready()
    rosout = nodes.start("sub.py", "/rosout", "rosgraph_msgs/Log", "--name", "rosout_reader")
    rosout.ready()
    api = nodes.start("api_node.py")
    report = api.expect(lambda d: "hooks" in d, timeout=30)
    assert report == {
        "has": True, "gain": 2.5, "config": {"a": 1, "b": {"c": "x"}}, "leaf": "x",
        "deleted": True, "default": 7, "delete_missing": "KeyError",
        "wait_timeout": True, "feed": "fed", "published": True,
        "is_shutdown": True, "sleep_raised": True, "hooks": ["plain", "test over"],
    }
    assert api.wait() == 0
    assert any(line.startswith("[ERROR] [") and line.endswith("]: an error")
               for line in api.stderr_lines)
    log = rosout.expect(lambda d: d.get("msg", {}).get("name") == "/api", timeout=10)["msg"]
    assert log["msg"] == "hello log" and log["level"] == 2
    assert log["function"] == "<module>" and log["file"].endswith("api_node.py")
    with xmlrpc.client.ServerProxy(nodes.master_uri) as proxy:
        state = proxy.getSystemState("/t")[2]
    assert all("/api" not in names for group in state for _, names in group)
