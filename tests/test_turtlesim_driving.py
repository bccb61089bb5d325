"""Steering rules of turtlesim's scripted drivers, and teleop's key decoding."""
from __future__ import annotations

import importlib.machinery
import importlib.util
import math
import sys
from pathlib import Path

import pytest

PKG = Path(__file__).resolve().parent.parent / "packages" / "turtlesim"
sys.path.insert(0, str(PKG / "src"))

from turtlesim_core import world as W  # noqa: E402
from turtlesim_core.driving import Circuit, square_corners, steer  # noqa: E402


def load_script(path: Path):
    loader = importlib.machinery.SourceFileLoader(path.name.replace(".", "_"), str(path))
    spec = importlib.util.spec_from_loader(loader.name, loader)
    module = importlib.util.module_from_spec(spec)
    loader.exec_module(module)
    return module


def test_steer_turns_in_place_when_goal_is_behind():
    linear, angular = steer(0, 0, 0.0, -1.0, 0.1, speed=1.0)
    assert linear == 0.0 and angular > 0


def test_steer_drives_straight_when_aligned():
    assert steer(0, 0, 0.0, 3.0, 0.0, speed=1.5) == pytest.approx((1.5, 0.0))


def test_circuit_visits_every_waypoint_in_order_and_never_hits_a_wall():
    world = W.World()
    turtle = world.reset(W.DEFAULT_BACKGROUND)
    circuit = Circuit(pause=0.5)
    visited = []
    for k in range(int(60 / W.UPDATE_PERIOD)):
        now = k * W.UPDATE_PERIOD
        before = circuit.index
        turtle.command(*circuit.command(turtle.x, turtle.y, turtle.theta, now), now)
        if circuit.index != before:
            visited.append(before)
        assert not world.step(now)
    assert visited[:5] == [0, 1, 2, 3, 4]


def test_circuit_stands_still_while_pausing():
    circuit = Circuit(waypoints=((1.0, 0.0), (5.0, 0.0)), pause=2.0)
    assert circuit.command(1.0, 0.0, 0.0, now=10.0) == (0.0, 0.0)  # reached: pause starts
    assert circuit.command(1.0, 0.0, 0.0, now=11.9) == (0.0, 0.0)
    assert circuit.command(1.0, 0.0, 0.0, now=12.1)[0] > 0.0


def test_draw_square_path_is_a_closed_two_metre_square():
    corners = square_corners(1.0, 1.0)
    assert corners[-1] == (1.0, 1.0)
    sides = [math.dist(a, b) for a, b in zip(((1.0, 1.0),) + corners, corners, strict=False)]
    assert sides == pytest.approx([2.0] * 4)


def test_teleop_decodes_arrow_keys_and_quit():
    teleop = load_script(PKG / "scripts" / "turtle_teleop_key")
    moves, quit_pressed, rest = teleop.parse_keys(b"\x1b[A\x1b[D\x1b[")
    assert moves == [(1.0, 0.0), (0.0, 1.0)] and not quit_pressed and rest == b"\x1b["
    moves, quit_pressed, _ = teleop.parse_keys(b"\x1b[Bq\x1b[A")
    assert moves == [(-1.0, 0.0)] and quit_pressed
