"""turtlebot_teleop_key's rules: key layout, speed scaling, ramp, dead-man stop."""
from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

PACKAGES = Path(__file__).resolve().parent.parent / "packages"
sys.path.insert(0, str(PACKAGES / "turtlebot_teleop" / "src"))

from turtlebot_teleop.keys import Teleop  # noqa: E402


def run(teleop: Teleop, cycles: int, pressed: bool = True) -> tuple[float, float]:
    for _ in range(cycles):
        result = teleop.cycle(pressed)
    return result


def test_forward_key_ramps_up_to_scale_linear():
    t = Teleop(scale_linear=0.5, scale_angular=1.5, linear_step=0.02)
    assert t.key("i")
    assert t.cycle(True) == pytest.approx((0.02, 0.0))
    assert run(t, 30) == pytest.approx((0.5, 0.0))


@pytest.mark.parametrize("key, sign", [("j", (0, 1)), ("l", (0, -1)), (",", (-1, 0)),
                                       ("u", (1, 1)), ("m", (-1, -1))])
def test_key_layout(key, sign):
    t = Teleop(scale_linear=0.4, scale_angular=1.0)
    t.key(key)
    assert run(t, 50) == pytest.approx((0.4 * sign[0], 1.0 * sign[1]))


def test_letting_go_decays_to_a_stop():
    t = Teleop(idle_cycles=4)
    t.key("i")
    run(t, 30)
    assert run(t, 4, pressed=False)[0] > 0       # still within the dead-man window
    assert run(t, 60, pressed=False) == (0.0, 0.0)


def test_stop_keys_stop_at_once():
    for key in ("k", " "):
        t = Teleop()
        t.key("i")
        run(t, 30)
        t.key(key)
        assert t.cycle(True) == (0.0, 0.0)


def test_speed_keys_scale_targets():
    t = Teleop(scale_linear=1.0, scale_angular=1.0)
    t.key("q")
    assert (t.scale_linear, t.scale_angular) == pytest.approx((1.1, 1.1))
    t.key("x")
    t.key("e")
    assert (t.scale_linear, t.scale_angular) == pytest.approx((0.99, 1.21))


def test_unknown_keys_are_ignored():
    t = Teleop()
    assert t.key("?") is False and t.direction == (0, 0)


def test_keyboard_teleop_launch_feeds_the_mux_teleop_input(tmp_path):
    result = subprocess.run([sys.executable, "-m", "orchestra", "launch", "turtlebot_teleop",
                             "keyboard_teleop.launch", "--dump-plan"], capture_output=True,
                            text=True, timeout=60, env={**__import__("os").environ,
                                                        "ROS_HOME": str(tmp_path)})
    assert result.returncode == 0, result.stderr
    plan = json.loads(result.stdout)
    (teleop,) = plan["nodes"]
    assert teleop["type"] == "turtlebot_teleop_key"
    assert teleop["remap_args"] == [["turtlebot_teleop_keyboard/cmd_vel", "cmd_vel_mux/input/teleop"]]
    assert plan["params"]["/turtlebot_teleop_keyboard/scale_linear"] == 0.5
