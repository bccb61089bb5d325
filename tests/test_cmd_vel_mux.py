"""yocs_cmd_vel_mux's priority/timeout rules and its configuration checks, without processes."""
from __future__ import annotations

import sys
from pathlib import Path

import pytest

PACKAGES = Path(__file__).resolve().parent.parent / "packages"
sys.path.insert(0, str(PACKAGES / "yocs_cmd_vel_mux" / "src"))

from yocs_cmd_vel_mux.mux import IDLE, CmdVelMux, MuxConfigError, load_config, parse_config  # noqa: E402

CONFIG = {"subscribers": [
    {"name": "Safety", "topic": "input/safety_controller", "timeout": 0.2, "priority": 10},
    {"name": "Teleop", "topic": "input/teleop", "timeout": 1.0, "priority": 7},
    {"name": "Navigation", "topic": "input/navi", "timeout": 1.0, "priority": 5},
]}
SAFETY, TELEOP, NAVI = 0, 1, 2


@pytest.fixture
def mux() -> CmdVelMux:
    return CmdVelMux(parse_config(CONFIG))


def test_first_message_takes_an_idle_mux(mux):
    assert mux.active_name == IDLE
    assert mux.on_message(NAVI, 0.0) == (True, True)
    assert mux.active_name == "Navigation"


def test_higher_priority_overrides_active_input(mux):
    mux.on_message(NAVI, 0.0)
    assert mux.on_message(TELEOP, 0.1) == (True, True)
    assert mux.active_name == "Teleop"


def test_lower_priority_is_blocked_while_higher_is_fresh(mux):
    mux.on_message(TELEOP, 0.0)
    assert mux.on_message(NAVI, 0.5) == (False, False)
    assert mux.active_name == "Teleop"


def test_active_input_keeps_forwarding_without_change(mux):
    mux.on_message(TELEOP, 0.0)
    assert mux.on_message(TELEOP, 0.5) == (True, False)


def test_lower_priority_takes_over_after_active_times_out(mux):
    mux.on_message(TELEOP, 0.0)
    assert mux.on_message(NAVI, 1.5) == (True, True)
    assert mux.active_name == "Navigation"


def test_expire_releases_only_after_own_timeout(mux):
    mux.on_message(SAFETY, 0.0)
    assert mux.expire(0.15) is False
    assert mux.expire(0.25) is True
    assert mux.active_name == IDLE
    assert mux.expire(0.3) is False


def test_teleop_keeps_ownership_as_long_as_it_talks(mux):
    t = 0.0
    mux.on_message(TELEOP, t)
    for _ in range(10):
        t += 0.5
        assert mux.on_message(NAVI, t)[0] is False
        assert mux.on_message(TELEOP, t)[0] is True


def test_publisher_key_names_the_output():
    assert parse_config({**CONFIG, "publisher": "cmd_vel"}).output == "cmd_vel"
    assert parse_config(CONFIG).output == "output"


def test_duplicate_priorities_are_rejected():
    bad = {"subscribers": [dict(CONFIG["subscribers"][0]),
                           {**CONFIG["subscribers"][1], "priority": 10}]}
    with pytest.raises(MuxConfigError, match="priority 10"):
        parse_config(bad, "mux.yaml")


@pytest.mark.parametrize("entry, message", [
    ({"name": "x", "topic": "t", "timeout": 1.0}, "lacks priority"),
    ({"name": "x", "topic": "t", "timeout": 0, "priority": 1}, "timeout must be > 0"),
    ({"name": "x", "topic": "t", "timeout": "soon", "priority": 1}, "must be a number"),
    ({"name": "x", "topic": "t", "timeout": 1, "priority": -1}, "unsigned"),
])
def test_bad_subscriber_entries_are_rejected_with_reason(entry, message):
    with pytest.raises(MuxConfigError, match=message):
        parse_config({"subscribers": [entry]}, "mux.yaml")


def test_missing_subscribers_list_is_rejected():
    with pytest.raises(MuxConfigError, match="subscribers"):
        parse_config({"publisher": "out"})


def test_load_config_names_file_and_line_of_yaml_errors(tmp_path):
    path = tmp_path / "mux.yaml"
    path.write_text("subscribers:\n  - name: [unclosed\n")
    with pytest.raises(MuxConfigError) as info:
        load_config(str(path))
    assert str(path) in str(info.value)


def test_load_config_missing_file(tmp_path):
    with pytest.raises(MuxConfigError, match="not found"):
        load_config(str(tmp_path / "nope.yaml"))


def test_turtlebot_mux_yaml_is_valid():
    config = load_config(str(PACKAGES / "turtlebot_bringup" / "param" / "mux.yaml"))
    by_name = {i.name: i for i in config.inputs}
    assert by_name["Teleoperation"].topic == "input/teleop"
    assert by_name["Safe reactive controller"].priority > by_name["Teleoperation"].priority
