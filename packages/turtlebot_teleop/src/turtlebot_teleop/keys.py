"""Keyboard teleop rules (pure): which key asks for which motion, and the ramp towards it.

Layout of the TurtleBot teleop (a 3x3 block around ``k``)::

    u  i  o        forward-left   forward   forward-right
    j  k  l        turn left      stop      turn right
    m  ,  .        back-left      back      back-right

``q``/``z`` scale both speeds by 1.1/0.9, ``w``/``x`` only linear, ``e``/``c`` only angular;
space or ``k`` stop at once. Motion keys set a TARGET; the published command moves towards it
by at most ``linear_step``/``angular_step`` per cycle (a built-in smoother: a Kobuki jerked
from 0 to 0.5 m/s in one cycle pops a wheelie). With no key for ``idle_cycles`` cycles the
target returns to zero, so letting go of the key stops the robot like a dead-man switch.
"""
from __future__ import annotations

from dataclasses import dataclass

MOVES = {"i": (1, 0), "o": (1, -1), "j": (0, 1), "l": (0, -1), "u": (1, 1),
         ",": (-1, 0), ".": (-1, 1), "m": (-1, -1)}
SPEEDS = {"q": (1.1, 1.1), "z": (0.9, 0.9), "w": (1.1, 1.0), "x": (0.9, 1.0),
          "e": (1.0, 1.1), "c": (1.0, 0.9)}
STOP = {" ", "k"}


def _approach(current: float, target: float, step: float) -> float:
    if target > current:
        return min(target, current + step)
    return max(target, current - step)


@dataclass
class Teleop:
    scale_linear: float = 0.5
    scale_angular: float = 1.5
    linear_step: float = 0.02      # m/s per cycle
    angular_step: float = 0.1      # rad/s per cycle
    idle_cycles: int = 4
    direction: tuple[int, int] = (0, 0)
    linear: float = 0.0            # the command being published
    angular: float = 0.0
    _idle: int = 0

    @property
    def target(self) -> tuple[float, float]:
        return self.direction[0] * self.scale_linear, self.direction[1] * self.scale_angular

    def key(self, key: str) -> bool:
        """Apply one key press; False for keys that mean nothing (ignored)."""
        if key in MOVES:
            self.direction = MOVES[key]
        elif key in SPEEDS:
            lin, ang = SPEEDS[key]
            self.scale_linear *= lin
            self.scale_angular *= ang
        elif key in STOP:
            self.direction = (0, 0)
            self.linear = self.angular = 0.0
        else:
            return False
        self._idle = 0
        return True

    def cycle(self, pressed: bool) -> tuple[float, float]:
        """One publishing cycle; ``pressed``: did any key arrive since the last one."""
        if pressed:
            self._idle = 0
        else:
            self._idle += 1
            if self._idle > self.idle_cycles:
                self.direction = (0, 0)
        target_linear, target_angular = self.target
        self.linear = _approach(self.linear, target_linear, self.linear_step)
        self.angular = _approach(self.angular, target_angular, self.angular_step)
        return self.linear, self.angular
