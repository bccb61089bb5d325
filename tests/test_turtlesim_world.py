"""turtlesim's simulation without processes: kinematics, walls, pens, services' rules, PNG."""
from __future__ import annotations

import math
import struct
import sys
import zlib
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "packages" / "turtlesim" / "src"))

from turtlesim_core import world as W  # noqa: E402
from turtlesim_core.canvas import Canvas  # noqa: E402
from turtlesim_core.png import encode_png, write_png  # noqa: E402


def read_png(data: bytes) -> tuple[int, int, bytes]:
    """Decode the subset encode_png writes (RGB8, filter 0) independently of the encoder."""
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    pos, idat, width = 8, b"", 0
    while pos < len(data):
        (length,) = struct.unpack(">I", data[pos:pos + 4])
        kind, body = data[pos + 4:pos + 8], data[pos + 8:pos + 8 + length]
        (crc,) = struct.unpack(">I", data[pos + 8 + length:pos + 12 + length])
        assert crc == zlib.crc32(kind + body) & 0xFFFFFFFF
        if kind == b"IHDR":
            width, height, depth, ctype = struct.unpack(">IIBB", body[:10])
            assert (depth, ctype) == (8, 2)
        elif kind == b"IDAT":
            idat += body
        pos += 12 + length
    raw = zlib.decompress(idat)
    stride = width * 3 + 1
    rows = [raw[y * stride:(y + 1) * stride] for y in range(height)]
    assert all(r[0] == 0 for r in rows)
    return width, height, b"".join(r[1:] for r in rows)


def fresh_world():
    world = W.World()
    turtle = world.reset(W.DEFAULT_BACKGROUND)
    return world, turtle


def test_world_geometry_matches_turtlesim():
    assert W.WORLD_WIDTH == pytest.approx(11.088889, abs=1e-6)
    _, turtle = fresh_world()
    assert turtle.name == "turtle1"
    assert (turtle.x, turtle.y, turtle.theta) == pytest.approx((5.544445, 5.544445, 0.0), abs=1e-6)


def test_forward_command_moves_along_heading_for_one_second_then_times_out():
    world, turtle = fresh_world()
    turtle.command(1.0, 0.0, now=0.0)
    t = 0.0
    for _ in range(125):  # 2 s of 16 ms ticks
        t += W.UPDATE_PERIOD
        world.step(t)
    # moves until the command is older than 1 s (62 ticks), then stops
    assert turtle.x - 5.544445 == pytest.approx(62 * 0.016, abs=0.02)
    assert turtle.linear_velocity == 0.0


def test_turning_keeps_theta_in_minus_pi_to_pi():
    world, turtle = fresh_world()
    for i in range(200):
        turtle.command(0.0, 2.0, now=i * 0.016)
        world.step(i * 0.016)
        assert -math.pi <= turtle.theta < math.pi
    assert W.normalize_angle(math.pi) == pytest.approx(-math.pi)


def test_circle_radius_is_linear_over_angular_velocity():
    world, turtle = fresh_world()
    for i in range(int(math.pi / 0.016)):  # half a turn at 1 rad/s
        turtle.command(1.0, 1.0, now=i * 0.016)
        world.step(i * 0.016)
    assert turtle.y - 5.544445 == pytest.approx(2.0, abs=0.05)
    assert turtle.x == pytest.approx(5.544445, abs=0.05)


def test_wall_clamps_position_and_reports_the_hit():
    world, turtle = fresh_world()
    hits = []
    for i in range(100):
        turtle.command(10.0, 0.0, now=i * 0.016)
        hits += world.step(i * 0.016)
    assert turtle.x == W.WORLD_WIDTH
    assert turtle.y == pytest.approx(5.544445, abs=1e-6)
    assert hits and hits[0] is turtle


def test_pen_draws_trail_and_pen_off_does_not():
    world, turtle = fresh_world()
    world.teleport_absolute("turtle1", 2.0, 2.0, 0.0)
    px, py = W.to_pixels(3.5, 3.5)
    assert world.canvas.get(int(px), int(py)) == W.DEFAULT_PEN
    world.set_pen("turtle1", (255, 0, 0), 5, off=True)
    world.teleport_absolute("turtle1", 2.0, 8.0, 0.0)
    px, py = W.to_pixels(2.0, 5.0)
    assert world.canvas.get(int(px), int(py)) == W.DEFAULT_BACKGROUND
    world.set_pen("turtle1", (255, 0, 0), 5, off=False)
    world.teleport_absolute("turtle1", 8.0, 8.0, 0.0)
    px, py = W.to_pixels(5.0, 8.0)
    assert world.canvas.get(int(px), int(py)) == (255, 0, 0)
    assert world.color_under(turtle) == (255, 0, 0)


def test_teleport_relative_turns_first_then_moves():
    world, turtle = fresh_world()
    world.teleport_relative("turtle1", 1.0, math.pi / 2)
    assert (turtle.x, turtle.y) == pytest.approx((5.544445, 6.544445), abs=1e-6)
    assert turtle.theta == pytest.approx(math.pi / 2)


def test_spawn_names_unnamed_turtles_and_refuses_duplicates():
    world, _ = fresh_world()
    assert world.spawn("", 1, 1, 0).name == "turtle2"
    assert world.spawn("leonardo", 1, 1, 0).name == "leonardo"
    with pytest.raises(W.WorldError, match=r"A turtle named \[leonardo\] already exists"):
        world.spawn("leonardo", 2, 2, 0)
    world.kill("turtle2")
    with pytest.raises(W.WorldError, match="does not exist"):
        world.kill("turtle2")


def test_reset_kills_everyone_clears_and_respawns_turtle1():
    world, _ = fresh_world()
    world.spawn("", 1, 1, 0)
    world.teleport_absolute("turtle1", 1.0, 1.0, 0.0)
    turtle = world.reset((0, 0, 0))
    assert list(world.turtles) == ["turtle1"] and turtle.x == pytest.approx(5.544445)
    assert set(world.canvas.pixels) == {0}


def test_render_draws_turtles_without_touching_the_trail_canvas():
    world, turtle = fresh_world()
    before = bytes(world.canvas.pixels)
    frame = world.render()
    assert bytes(world.canvas.pixels) == before
    px, py = W.to_pixels(turtle.x, turtle.y)
    assert frame.get(int(px), int(py)) != W.DEFAULT_BACKGROUND


def test_png_roundtrip_preserves_every_pixel(tmp_path):
    canvas = Canvas(7, 5, (1, 2, 3))
    canvas.draw_line(0, 0, 6, 4, (250, 10, 20), 1)
    path = tmp_path / "c.png"
    write_png(str(path), 7, 5, canvas.pixels)
    assert read_png(path.read_bytes()) == (7, 5, bytes(canvas.pixels))


def test_png_rejects_wrong_buffer_size():
    with pytest.raises(ValueError):
        encode_png(2, 2, b"\x00" * 11)
