"""The TurtleBot node executables refuse bad situations with a clear message and exit 1
(nothing half-running): no base for the kinect breaker, no robot_description, a bad analyzer
configuration, a mux without its YAML."""
from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from orchestra.master import start_master

PACKAGES = Path(__file__).resolve().parent.parent / "packages"

pytestmark = pytest.mark.timeout(60)


@pytest.fixture
def run(tmp_path):
    handle = start_master(host="127.0.0.1", port=0)
    env = {k: v for k, v in os.environ.items() if not k.startswith("ROS_")}
    env.update(ROS_MASTER_URI=handle.uri, ROS_HOME=str(tmp_path / "ros_home"))

    def run_node(script: str, *args: str) -> subprocess.CompletedProcess:
        return subprocess.run([sys.executable, str(PACKAGES / script), *args], env=env,
                              capture_output=True, text=True, timeout=30)
    yield run_node
    handle.shutdown()


def test_kinect_breaker_enabler_fails_when_no_base_offers_the_service(run):
    result = run("turtlebot_bringup/scripts/kinect_breaker_enabler.py", "_timeout:=0.5")
    assert result.returncode == 1
    assert "/mobile_base/set_digital_outputs" in result.stdout + result.stderr


def test_robot_state_publisher_without_description_exits_1(run):
    result = run("robot_state_publisher/scripts/robot_state_publisher")
    assert result.returncode == 1
    assert "/robot_description is not set" in result.stdout + result.stderr


def test_robot_state_publisher_rejects_invalid_urdf(run):
    result = run("robot_state_publisher/scripts/robot_state_publisher",
                 "__name:=rsp", "robot_description:=/rsp/bad", "_bad:=<robot><link/></robot>")
    assert result.returncode == 1
    assert "needs a name" in result.stdout + result.stderr


def test_aggregator_with_unknown_analyzer_type_exits_1(run):
    result = run("diagnostic_aggregator/scripts/aggregator_node",
                 "_analyzers:={motors: {type: diagnostic_aggregator/Nope, path: M}}")
    assert result.returncode == 1
    assert "unsupported type 'diagnostic_aggregator/Nope'" in result.stdout + result.stderr


def test_mux_without_yaml_cfg_file_fails_to_load(run):
    result = run("nodelet/scripts/nodelet", "standalone", "yocs_cmd_vel_mux/CmdVelMuxNodelet",
                 "__name:=mux")
    assert result.returncode != 0
    assert "/mux/yaml_cfg_file is not set" in result.stdout + result.stderr
    assert "Traceback" not in result.stderr
