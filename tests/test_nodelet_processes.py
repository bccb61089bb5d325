"""nodelet as processes: a manager hosting a loader's nodelet under the loader's name, a load
that fails, the loader following its manager's death, unload on Ctrl-C, standalone mode."""
from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
import xmlrpc.client
from pathlib import Path

import pytest

PACKAGES = Path(__file__).resolve().parent.parent / "packages"
NODELET = str(PACKAGES / "nodelet" / "scripts" / "nodelet")
MUX_YAML = str(PACKAGES / "yocs_cmd_vel_mux" / "param" / "example.yaml")

pytestmark = pytest.mark.timeout(60)


@pytest.fixture
def spawn(master, tmp_path):
    env = {k: v for k, v in os.environ.items() if not k.startswith("ROS_")}
    env.update(ROS_MASTER_URI=master.uri, ROS_HOME=str(tmp_path / "ros_home"))
    procs: list[subprocess.Popen] = []

    def start(*args: str) -> subprocess.Popen:
        proc = subprocess.Popen([sys.executable, NODELET, *args], env=env, text=True,
                                stdout=subprocess.PIPE, stderr=subprocess.STDOUT)
        procs.append(proc)
        return proc
    yield start
    for proc in procs:
        if proc.poll() is None:
            proc.kill()
        proc.wait()
        if proc.stdout is not None:
            proc.stdout.close()


def publishers(master, topic: str) -> list[str]:
    with xmlrpc.client.ServerProxy(master.uri) as proxy:
        state = proxy.getSystemState("/test")[2]
    return next((nodes for name, nodes in state[0] if name == topic), [])


def wait_until(predicate, timeout: float = 15.0) -> bool:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if predicate():
            return True
        time.sleep(0.1)
    return False


def read_until(proc: subprocess.Popen, text: str) -> str:
    """The process's output up to the first line containing ``text`` (or to its end)."""
    seen = []
    for line in proc.stdout:
        seen.append(line)
        if text in line:
            break
    return "".join(seen)


def test_loaded_nodelet_lives_in_the_manager_under_the_loaders_name(master, spawn):
    manager = spawn("manager", "__name:=mgr")
    loader = spawn("load", "yocs_cmd_vel_mux/CmdVelMuxNodelet", "mgr", "__name:=mux",
                   f"_yaml_cfg_file:={MUX_YAML}", "mux/output:=/cmd_vel")
    # the topics are the nodelet's (/mux/...), registered by the process hosting it (/mgr)
    assert wait_until(lambda: publishers(master, "/mux/active") == ["/mgr"])
    assert publishers(master, "/cmd_vel") == ["/mgr"]      # the loader's remap applied
    loader.send_signal(signal.SIGINT)
    assert loader.wait(timeout=15) == 0
    assert wait_until(lambda: publishers(master, "/mux/active") == [])   # unloaded
    assert manager.poll() is None


def test_unknown_nodelet_type_fails_the_loader_not_the_manager(master, spawn):
    manager = spawn("manager", "__name:=mgr")
    loader = spawn("load", "nobody/Nothing", "mgr", "__name:=bad")
    assert loader.wait(timeout=20) == 1
    assert "refused to load" in loader.stdout.read()
    assert manager.poll() is None


def test_loader_exits_when_its_manager_dies(master, spawn):
    manager = spawn("manager", "__name:=mgr")
    loader = spawn("load", "yocs_cmd_vel_mux/CmdVelMuxNodelet", "mgr", "__name:=mux",
                   f"_yaml_cfg_file:={MUX_YAML}")
    assert wait_until(lambda: publishers(master, "/mux/active") == ["/mgr"])
    # the manager registers the nodelet's topics before its load reply reaches the loader:
    # stop it only once the loader knows the load succeeded
    assert "loaded into /mgr" in read_until(loader, "loaded into")
    manager.send_signal(signal.SIGINT)
    assert manager.wait(timeout=15) == 0
    assert loader.wait(timeout=15) == 1
    assert "went away" in loader.stdout.read()


def test_standalone_runs_the_nodelet_as_its_own_node(master, spawn):
    solo = spawn("standalone", "yocs_cmd_vel_mux/CmdVelMuxNodelet", "__name:=solo",
                 f"_yaml_cfg_file:={MUX_YAML}")
    assert wait_until(lambda: publishers(master, "/solo/active") == ["/solo"])
    solo.send_signal(signal.SIGINT)
    assert solo.wait(timeout=15) == 0


def test_usage_error_exits_2(spawn):
    proc = spawn("load", "only_a_type")
    assert proc.wait(timeout=15) == 2
    assert "usage: nodelet" in proc.stdout.read()


def test_killed_loader_is_unloaded_and_a_respawned_one_loads_again(master, spawn):
    manager = spawn("manager", "__name:=mgr")
    args = ("load", "yocs_cmd_vel_mux/CmdVelMuxNodelet", "mgr", "__name:=mux",
            f"_yaml_cfg_file:={MUX_YAML}")
    loader = spawn(*args)
    assert wait_until(lambda: publishers(master, "/mux/active") == ["/mgr"])
    loader.kill()                       # no chance to unload: the manager must notice
    loader.wait()
    assert wait_until(lambda: publishers(master, "/mux/active") == [], timeout=10)
    respawned = spawn(*args)
    assert wait_until(lambda: publishers(master, "/mux/active") == ["/mgr"])
    assert respawned.poll() is None and manager.poll() is None
