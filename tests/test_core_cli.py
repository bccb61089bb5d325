"""``orchestra core`` runs a standalone master like roscore."""
from __future__ import annotations

import os
import signal
import subprocess
import sys
import xmlrpc.client
from pathlib import Path

import pytest

from orchestra.master import master_is_up

sys.path.insert(0, str(Path(__file__).resolve().parent / "node_fixtures"))
from harness import free_port, wait_for_cpu  # noqa: E402

pytestmark = pytest.mark.timeout(60)


@pytest.fixture
def core():
    """Start ``orchestra core`` with the given args; yields (process, master URI)."""
    procs: list[subprocess.Popen] = []

    def start(*args: str, env: dict[str, str] | None = None) -> tuple[subprocess.Popen, str]:
        full_env = {**os.environ, **(env or {})}
        full_env.pop("ROS_IP", None)
        full_env.pop("ROS_HOSTNAME", None)
        proc = subprocess.Popen([sys.executable, "-m", "orchestra", "core", *args],
                                stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                                env=full_env)
        procs.append(proc)
        line = proc.stdout.readline()
        assert line.startswith("ROS_MASTER_URI="), line + proc.stderr.read()
        return proc, line.strip().split("=", 1)[1]
    yield start
    for proc in procs:
        if proc.poll() is None:
            proc.kill()
        proc.wait(10)
        proc.stdout.close()
        proc.stderr.close()


def test_core_serves_and_sets_roscore_params(core):
    proc, uri = core("-p", "0")
    with xmlrpc.client.ServerProxy(uri) as m:
        assert m.getPid("/t") == [1, "", proc.pid]
        assert m.getUri("/t")[2] == uri
        params = m.getParam("/t", "/")[2]
    assert params["rosdistro"].endswith("\n") and params["rosversion"].endswith("\n")
    assert len(params["run_id"]) == 36  # a uuid, as roslaunch writes it


def test_core_stops_cleanly_on_sigint(core):
    proc, uri = core("-p", "0")
    proc.send_signal(signal.SIGINT)
    assert proc.wait(10) == 0
    assert not master_is_up(uri, timeout=0.5)


def test_core_stops_on_xmlrpc_shutdown(core):
    proc, uri = core("-p", "0")
    with xmlrpc.client.ServerProxy(uri) as m:
        assert m.shutdown("/t", "test")[0] == 1
    assert proc.wait(10) == 0


def test_core_takes_port_from_ros_master_uri(core):
    port = free_port()
    proc, uri = core(env={"ROS_MASTER_URI": f"http://localhost:{port}/"})
    assert uri == f"http://127.0.0.1:{port}/"
    assert master_is_up(uri)


def test_second_core_on_same_port_refuses_with_clear_message(core):
    proc, uri = core("-p", "0")
    port = uri.rsplit(":", 1)[1].strip("/")
    second = subprocess.run([sys.executable, "-m", "orchestra", "core", "-p", port],
                            capture_output=True, text=True, timeout=30)
    assert second.returncode == 1
    assert "already running" in second.stderr and "Traceback" not in second.stderr
    assert master_is_up(uri)  # the first one is untouched


@pytest.mark.parametrize("moment", [0.0, 0.03, 0.06])
def test_ctrl_c_in_cores_first_moments_stops_it_and_its_master(moment):
    """As for launch: a Ctrl-C while core imports and starts its master is never lost (it
    was dropped when it landed in an import-lock callback). SIGINT after the process has
    used ``moment`` s of CPU (or once it is up), twice each; the port must be free afterwards."""
    for _ in range(2):
        port = free_port()
        env = {k: v for k, v in os.environ.items() if k not in ("ROS_IP", "ROS_HOSTNAME")}
        proc = subprocess.Popen([sys.executable, "-m", "orchestra", "core", "-p", str(port),
                                 "--no-rosout"], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                text=True, env=env)
        try:
            wait_for_cpu(proc, moment)
            proc.send_signal(signal.SIGINT)
            out, err = proc.communicate(timeout=30)
        finally:   # a failed wait must not leave a core serving
            if proc.poll() is None:
                proc.kill()
                proc.communicate()
        # -SIGINT: before Python's own handler existed; 130: during the imports; 0: stopped
        assert proc.returncode in (-signal.SIGINT, 130, 0), err
        assert "Traceback" not in err and "Exception ignored" not in err, err
        assert not master_is_up(f"http://127.0.0.1:{port}/", timeout=0.5)
