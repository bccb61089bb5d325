"""The turtle canvas: an RGB raster the pens draw on, plus the turtles drawn on top.

Pixels, not metres: the world converts (turtlesim's 45 px per metre, y pointing up in the
world and down in the image). Lines are drawn by stamping a round pen tip along the segment,
which gives Qt-like round caps and joins for the short per-tick segments turtles leave.
"""
from __future__ import annotations

import math
from collections.abc import Iterable, Sequence

Color = tuple[int, int, int]


class Canvas:
    """A ``width`` x ``height`` RGB image (bytearray, row-major) with a pen-line primitive."""

    def __init__(self, width: int, height: int, background: Color):
        self.width = width
        self.height = height
        self.pixels = bytearray(bytes(background) * (width * height))

    def fill(self, color: Color) -> None:
        self.pixels[:] = bytes(color) * (self.width * self.height)

    def get(self, x: int, y: int) -> Color:
        i = (y * self.width + x) * 3
        return (self.pixels[i], self.pixels[i + 1], self.pixels[i + 2])

    def _disc(self, cx: float, cy: float, radius: float, color: bytes) -> None:
        r2 = radius * radius
        x0, x1 = max(0, int(math.floor(cx - radius))), min(self.width - 1, int(math.ceil(cx + radius)))
        y0, y1 = max(0, int(math.floor(cy - radius))), min(self.height - 1, int(math.ceil(cy + radius)))
        px = self.pixels
        for y in range(y0, y1 + 1):
            dy = y + 0.5 - cy
            row = y * self.width
            for x in range(x0, x1 + 1):
                dx = x + 0.5 - cx
                if dx * dx + dy * dy <= r2:
                    i = (row + x) * 3
                    px[i:i + 3] = color

    def draw_line(self, x0: float, y0: float, x1: float, y1: float, color: Color,
                  width: float) -> None:
        """A pen stroke ``width`` pixels wide from (x0, y0) to (x1, y1)."""
        radius = max(0.5, width / 2.0)
        c = bytes(color)
        length = math.hypot(x1 - x0, y1 - y0)
        steps = max(1, int(math.ceil(length / 0.5)))
        for k in range(steps + 1):
            t = k / steps
            self._disc(x0 + (x1 - x0) * t, y0 + (y1 - y0) * t, radius, c)

    def fill_polygon(self, points: Sequence[tuple[float, float]], color: Color) -> None:
        """Even-odd scanline fill; used to draw the turtles."""
        c = bytes(color)
        ys = [p[1] for p in points]
        y0, y1 = max(0, int(math.floor(min(ys)))), min(self.height - 1, int(math.ceil(max(ys))))
        n = len(points)
        for y in range(y0, y1 + 1):
            sy = y + 0.5
            xs = []
            for i in range(n):
                (ax, ay), (bx, by) = points[i], points[(i + 1) % n]
                if (ay <= sy < by) or (by <= sy < ay):
                    xs.append(ax + (sy - ay) * (bx - ax) / (by - ay))
            xs.sort()
            for a, b in zip(xs[0::2], xs[1::2], strict=False):
                xa, xb = max(0, int(math.ceil(a - 0.5))), min(self.width - 1, int(math.floor(b - 0.5)))
                if xb >= xa:
                    start = (y * self.width + xa) * 3
                    self.pixels[start:(y * self.width + xb + 1) * 3] = c * (xb - xa + 1)

    def copy(self) -> Canvas:
        other = Canvas.__new__(Canvas)
        other.width, other.height, other.pixels = self.width, self.height, bytearray(self.pixels)
        return other


def turtle_outline(cx: float, cy: float, heading: float, size: float) -> list[tuple[float, float]]:
    """A dart-shaped turtle of ``size`` pixels, nose along ``heading`` (radians, counter-clockwise
    with image y pointing down, so the world's yaw maps to -heading in image terms)."""
    shape = [(0.6, 0.0), (-0.4, 0.45), (-0.2, 0.0), (-0.4, -0.45)]
    cos_h, sin_h = math.cos(heading), math.sin(heading)
    out = []
    for u, v in shape:
        x, y = u * size, v * size
        # rotate counter-clockwise in world terms = clockwise in image rows
        out.append((cx + x * cos_h - y * sin_h, cy - (x * sin_h + y * cos_h)))
    return out


def draw_turtles(canvas: Canvas, turtles: Iterable[tuple[float, float, float]],
                 colors: Sequence[Color] = ((30, 160, 60), (230, 140, 20), (200, 40, 160)),
                 size: float = 22.0) -> Canvas:
    """A copy of ``canvas`` with a turtle dart at each (x_px, y_px, heading)."""
    out = canvas.copy()
    for i, (x, y, heading) in enumerate(turtles):
        out.fill_polygon(turtle_outline(x, y, heading, size), colors[i % len(colors)])
    return out
