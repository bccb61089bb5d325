"""The turtle world: turtlesim's kinematics, walls, pens and turtle bookkeeping.

Numbers are turtlesim's: a 500 x 500 px canvas at 45 px per metre (the turtle sprite's height),
so the world is (500 - 1) / 45 = 11.0889 m wide and turtle1 starts at its centre 5.544445; a
fixed 16 ms step (the Qt timer interval, used as dt whatever the wall clock did); a velocity
command is forgotten after 1 s; a turtle leaving the world is clamped back to the edge with a
warning; an "on" pen paints the segment travelled. Angles are kept in [-pi, pi).

No clocks or threads here: ``step(now)`` is given the time, so tests drive it directly.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

from turtlesim_core.canvas import Canvas, Color, draw_turtles

WIDTH_PX = 500
HEIGHT_PX = 500
PX_PER_METER = 45.0
WORLD_WIDTH = (WIDTH_PX - 1) / PX_PER_METER
WORLD_HEIGHT = (HEIGHT_PX - 1) / PX_PER_METER
UPDATE_PERIOD = 0.016
COMMAND_TIMEOUT = 1.0
DEFAULT_BACKGROUND: Color = (69, 86, 255)
DEFAULT_PEN: Color = (179, 184, 255)
DEFAULT_PEN_WIDTH = 3


class WorldError(Exception):
    """A request the simulator refuses (duplicate spawn name, unknown turtle)."""


def normalize_angle(angle: float) -> float:
    """Into [-pi, pi), as turtlesim keeps its orientation."""
    return angle - 2.0 * math.pi * math.floor((angle + math.pi) / (2.0 * math.pi))


@dataclass
class Pen:
    color: Color = DEFAULT_PEN
    width: int = DEFAULT_PEN_WIDTH
    on: bool = True


@dataclass
class Turtle:
    """One turtle's state, in world metres with y up."""

    name: str
    x: float
    y: float
    theta: float
    linear_velocity: float = 0.0
    angular_velocity: float = 0.0
    last_command: float = -math.inf
    pen: Pen = field(default_factory=Pen)

    def command(self, linear: float, angular: float, now: float) -> None:
        """A cmd_vel: only linear.x and angular.z matter to a turtle."""
        self.linear_velocity, self.angular_velocity, self.last_command = linear, angular, now

    def step(self, dt: float, now: float) -> tuple[tuple[float, float], bool]:
        """Advance by ``dt``; returns (previous position, whether a wall was hit)."""
        if now - self.last_command > COMMAND_TIMEOUT:
            self.linear_velocity = self.angular_velocity = 0.0
        old = (self.x, self.y)
        self.theta = normalize_angle(self.theta + self.angular_velocity * dt)
        x = self.x + math.cos(self.theta) * self.linear_velocity * dt
        y = self.y + math.sin(self.theta) * self.linear_velocity * dt
        hit = not (0.0 <= x <= WORLD_WIDTH and 0.0 <= y <= WORLD_HEIGHT)
        self.x = min(max(x, 0.0), WORLD_WIDTH)
        self.y = min(max(y, 0.0), WORLD_HEIGHT)
        return old, hit


def to_pixels(x: float, y: float) -> tuple[float, float]:
    """World metres (y up) to canvas pixels (y down)."""
    return x * PX_PER_METER, (WORLD_HEIGHT - y) * PX_PER_METER


class World:
    """All turtles and the path canvas. Callers serialise access (the node holds one lock)."""

    def __init__(self, background: Color = DEFAULT_BACKGROUND):
        self.canvas = Canvas(WIDTH_PX, HEIGHT_PX, background)
        self.turtles: dict[str, Turtle] = {}
        self._id_counter = 0

    # --- turtles -----------------------------------------------------------------------------

    def spawn(self, name: str, x: float, y: float, theta: float) -> Turtle:
        """Add a turtle; an empty name becomes the next free ``turtleN``."""
        if not name:
            while True:
                self._id_counter += 1
                name = f"turtle{self._id_counter}"
                if name not in self.turtles:
                    break
        elif name in self.turtles:
            raise WorldError(f"A turtle named [{name}] already exists")
        turtle = Turtle(name, float(x), float(y), normalize_angle(float(theta)))
        self.turtles[name] = turtle
        return turtle

    def kill(self, name: str) -> Turtle:
        try:
            return self.turtles.pop(name)
        except KeyError:
            raise WorldError(f"Tried to kill turtle [{name}], which does not exist") from None

    def get(self, name: str) -> Turtle:
        try:
            return self.turtles[name]
        except KeyError:
            raise WorldError(f"no turtle named [{name}]") from None

    def clear(self, background: Color) -> None:
        self.canvas.fill(background)

    def reset(self, background: Color) -> Turtle:
        """Everything back to start: canvas cleared, all turtles gone, turtle1 in the centre."""
        self.turtles.clear()
        self._id_counter = 0
        self.clear(background)
        return self.spawn("", WORLD_WIDTH / 2.0, WORLD_HEIGHT / 2.0, 0.0)

    # --- motion ------------------------------------------------------------------------------

    def _trail(self, turtle: Turtle, old: tuple[float, float]) -> None:
        if turtle.pen.on and old != (turtle.x, turtle.y):
            x0, y0 = to_pixels(*old)
            x1, y1 = to_pixels(turtle.x, turtle.y)
            self.canvas.draw_line(x0, y0, x1, y1, turtle.pen.color, turtle.pen.width)

    def step(self, now: float, dt: float = UPDATE_PERIOD) -> list[Turtle]:
        """One simulator tick; returns the turtles that hit a wall this tick."""
        walled = []
        for turtle in self.turtles.values():
            old, hit = turtle.step(dt, now)
            if hit:
                walled.append(turtle)
            self._trail(turtle, old)
        return walled

    def teleport_absolute(self, name: str, x: float, y: float, theta: float) -> None:
        turtle = self.get(name)
        old = (turtle.x, turtle.y)
        turtle.x, turtle.y, turtle.theta = float(x), float(y), normalize_angle(float(theta))
        self._trail(turtle, old)

    def teleport_relative(self, name: str, linear: float, angular: float) -> None:
        """Turn by ``angular`` first, then move ``linear`` along the new heading."""
        turtle = self.get(name)
        theta = normalize_angle(turtle.theta + angular)
        self.teleport_absolute(name, turtle.x + math.cos(theta) * linear,
                               turtle.y + math.sin(theta) * linear, theta)

    def set_pen(self, name: str, color: Color, width: int, off: bool) -> None:
        self.get(name).pen = Pen(color=color, width=width, on=not off)

    def color_under(self, turtle: Turtle) -> Color:
        """The canvas colour below a turtle (its color_sensor reading)."""
        px, py = to_pixels(turtle.x, turtle.y)
        return self.canvas.get(min(int(px), WIDTH_PX - 1), min(int(py), HEIGHT_PX - 1))

    def render(self) -> Canvas:
        """The canvas with every turtle drawn on top (what the window and snapshots show)."""
        return draw_turtles(self.canvas, [(*to_pixels(t.x, t.y), t.theta)
                                          for t in self.turtles.values()])
