"""draw_square as a process: it resets the simulator and draws the first sides of a 2 m square
from the centre (checked on the canvas snapshot written at shutdown)."""
from __future__ import annotations

import os
import signal
import subprocess
import time
from pathlib import Path

import pytest
from test_turtlesim_world import read_png

# orchestra's bundled packages, whatever ROS workspace the developer's shell points at
BUNDLED_ENV = {k: v for k, v in os.environ.items()
               if k not in ("ROS_PACKAGE_PATH", "CMAKE_PREFIX_PATH")}

SCRIPTS = Path(__file__).resolve().parent.parent / "packages" / "turtlesim" / "scripts"
PEN = (179, 184, 255)
CENTRE = (500 - 1) / 45.0 / 2


@pytest.fixture
def master():
    from orchestra.master import start_master
    handle = start_master(port=0)
    yield handle.uri
    handle.shutdown()


@pytest.mark.timeout(60)
def test_draw_square_draws_the_first_two_sides_from_the_centre(master, tmp_path):
    env = dict(BUNDLED_ENV, ROS_MASTER_URI=master)
    env.pop("DISPLAY", None)
    png = tmp_path / "square.png"
    procs = [subprocess.Popen([str(SCRIPTS / "turtlesim_node"), f"_snapshot:={png}"], env=env,
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)]
    procs.append(subprocess.Popen([str(SCRIPTS / "draw_square")], env=env,
                                  stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL))
    try:
        deadline = time.monotonic() + 30
        seen = False
        while time.monotonic() < deadline and not seen:  # the PNG is rewritten every second
            time.sleep(0.5)
            if png.exists():
                width, _, pixels = read_png(png.read_bytes())

                def on_pen(x: float, y: float, pixels: bytes = pixels, width: int = width) -> bool:
                    """Pen colour within a pixel of the metre point (x, y)."""
                    cx, cy = int(x * 45), int((CENTRE * 2 - y) * 45)
                    return any(tuple(pixels[((cy + dy) * width + cx + dx) * 3:
                                            ((cy + dy) * width + cx + dx) * 3 + 3]) == PEN
                               for dx in (-1, 0, 1) for dy in (-1, 0, 1))

                def side_drawn(x0: float, y0: float, x1: float, y1: float) -> bool:
                    # most of the side: the turtle itself may be sitting on part of it
                    points = [(x0 + (x1 - x0) * k / 20, y0 + (y1 - y0) * k / 20)
                              for k in range(2, 19)]
                    return sum(on_pen(x, y) for x, y in points) >= 0.7 * len(points)

                seen = (side_drawn(CENTRE, CENTRE, CENTRE + 2, CENTRE)  # east
                        and side_drawn(CENTRE + 2, CENTRE, CENTRE + 2, CENTRE + 2))  # north
        assert seen, "the first two sides of the square never appeared on the canvas"
    finally:
        for p in reversed(procs):
            p.send_signal(signal.SIGINT)
            try:
                p.wait(10)
            except subprocess.TimeoutExpired:
                p.kill()
                p.wait()
