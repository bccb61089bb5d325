"""turtlesim's message and service definitions are ROS's: their md5sums are the ones
``rosmsg md5`` / ``rossrv md5`` print, so orchestra's turtlesim talks to ROS tools and nodes."""
from __future__ import annotations

import pytest

from orchestra.node.msg import get_message_class, get_service_class


@pytest.fixture(autouse=True)
def bundled_packages_only(monkeypatch):
    # the definitions must come from orchestra's packages/turtlesim, not a ROS workspace
    for key in ("ROS_PACKAGE_PATH", "CMAKE_PREFIX_PATH"):
        monkeypatch.delenv(key, raising=False)


ROS_MD5 = {
    "turtlesim/Pose": "863b248d5016ca62ea2e895ae5265cf9",
    "turtlesim/Color": "353891e354491c51aabe32df673fb446",
}
ROS_SRV_MD5 = {
    "turtlesim/Spawn": "0b2d2e872a8e2887d5ed626f2bf2c561",
    "turtlesim/Kill": "c1f3d28f1b044c871e6eff2e9fc3c667",
    "turtlesim/SetPen": "9f452acce566bf0c0954594f69a8e41b",
    "turtlesim/TeleportAbsolute": "a130bc60ee6513855dc62ea83fcc5b20",
    "turtlesim/TeleportRelative": "9d5c2dcd348ac8f76ce2a4307bd63a13",
}


@pytest.mark.parametrize("msg_type, md5", sorted(ROS_MD5.items()))
def test_turtlesim_message_md5_matches_ros(msg_type, md5):
    assert get_message_class(msg_type)._md5sum == md5


@pytest.mark.parametrize("srv_type, md5", sorted(ROS_SRV_MD5.items()))
def test_turtlesim_service_md5_matches_ros(srv_type, md5):
    assert get_service_class(srv_type)._md5sum == md5


def test_spawn_response_carries_the_chosen_name():
    spawn = get_service_class("turtlesim/Spawn")
    assert spawn.Response(name="turtle2").name == "turtle2"
    assert spawn.Request()._type == "turtlesim/SpawnRequest"
