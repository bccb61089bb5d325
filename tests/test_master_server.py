"""Where the master listens: loopback unless ROS_IP/ROS_HOSTNAME or a flag says otherwise."""
from __future__ import annotations

import socket

import pytest

from orchestra.errors import OrchestraError
from orchestra.master import master_uri_from_env, port_from_uri
from orchestra.master.server import bind_address


def test_default_binds_loopback_only():
    assert bind_address(None, {}) == ("127.0.0.1", "127.0.0.1")


@pytest.mark.parametrize("var", ["ROS_IP", "ROS_HOSTNAME"])
def test_ros_ip_or_hostname_opens_all_interfaces_and_is_advertised(var):
    assert bind_address(None, {var: "robot.local"}) == ("0.0.0.0", "robot.local")


def test_localhost_ros_hostname_keeps_loopback():
    assert bind_address(None, {"ROS_HOSTNAME": "localhost"})[0] == "127.0.0.1"


def test_explicit_host_wins_and_wildcard_advertises_machine_name():
    assert bind_address("10.0.0.5", {"ROS_IP": "1.2.3.4"}) == ("10.0.0.5", "10.0.0.5")
    assert bind_address("0.0.0.0", {}) == ("0.0.0.0", socket.gethostname())


def test_master_uri_and_port_from_environment():
    assert master_uri_from_env({}) == "http://localhost:11311/"
    assert master_uri_from_env({"ROS_MASTER_URI": "http://h:1234/"}) == "http://h:1234/"
    assert port_from_uri("http://h:1234/") == 1234
    assert port_from_uri("http://h/") == 11311
    with pytest.raises(OrchestraError, match="invalid master URI"):
        port_from_uri("http://h:notaport/")
