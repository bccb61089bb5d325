"""Pure steering rules for the scripted drivers: the ``turtle_driver`` circuit and
``draw_square``. Kept out of the scripts so they are tested without processes."""
from __future__ import annotations

import math
from dataclasses import dataclass, field

from turtlesim_core.world import WORLD_HEIGHT, WORLD_WIDTH, normalize_angle

# corners of a loop well inside the walls, counter-clockwise, starting east of the centre
DEFAULT_CIRCUIT = ((8.5, 5.5), (8.5, 8.5), (2.5, 8.5), (2.5, 2.5), (8.5, 2.5))


def steer(x: float, y: float, theta: float, gx: float, gy: float, speed: float,
          turn_gain: float = 4.0, max_turn: float = 3.0) -> tuple[float, float]:
    """(linear, angular) towards goal (gx, gy): turn in place while facing away (more than
    ~30 degrees off), drive at ``speed`` once roughly aligned."""
    error = normalize_angle(math.atan2(gy - y, gx - x) - theta)
    angular = max(-max_turn, min(max_turn, turn_gain * error))
    linear = speed * math.cos(error) if abs(error) < 0.5 else 0.0
    return linear, angular


@dataclass
class Circuit:
    """Drive from waypoint to waypoint for ever, pausing ``pause`` seconds at each one.

    The pauses are what let a follower catch up: the tutorial listener's linear gain of 0.5 /s
    leaves it 2*v metres behind a turtle moving at v, and it closes that gap while we wait.
    """

    waypoints: tuple[tuple[float, float], ...] = DEFAULT_CIRCUIT
    speed: float = 1.0
    pause: float = 2.0
    reach: float = 0.15
    index: int = 0
    paused_until: float = field(default=-math.inf)

    def command(self, x: float, y: float, theta: float, now: float) -> tuple[float, float]:
        if now < self.paused_until:
            return 0.0, 0.0
        gx, gy = self.waypoints[self.index]
        if math.hypot(gx - x, gy - y) < self.reach:
            self.index = (self.index + 1) % len(self.waypoints)
            self.paused_until = now + self.pause
            return 0.0, 0.0
        return steer(x, y, theta, gx, gy, self.speed)


def inside_world(x: float, y: float) -> bool:
    return 0.0 <= x <= WORLD_WIDTH and 0.0 <= y <= WORLD_HEIGHT


def square_corners(x: float, y: float, side: float = 2.0) -> tuple[tuple[float, float], ...]:
    """The draw_square path from a start point: east, north, west, south, back home."""
    return ((x + side, y), (x + side, y + side), (x, y + side), (x, y))
