"""A simulated Kobuki base: differential-drive kinematics, encoders, gyro, battery, diagnostics.

Pure: nothing here touches the network, so the maths is unit-tested without processes. The
nodelet (``kobuki_node.nodelet``) owns the clock and the topics and calls ``KobukiBase.step``.

The simulation keeps the real driver's shape on purpose: the *true* motion produces wheel
encoder ticks (16-bit, wrapping) and a gyro heading, and odometry is then rebuilt from the
ticks exactly as a driver must do on a real robot. That makes the odometry code the same code
that would run against hardware, and lets tests pin tick wrap-around and heading source.
"""
from __future__ import annotations

import math
import random
from dataclasses import dataclass, field

# Kobuki's published geometry (kobuki_driver's parameters)
WHEEL_RADIUS = 0.035          # m
WHEEL_BASE = 0.230            # m, distance between the wheels
TICK_TO_RAD = 0.002436916871363930187454  # rad of wheel rotation per encoder tick
TICKS_WRAP = 65536            # encoders are uint16

OK, WARN, ERROR, STALE = 0, 1, 2, 3


@dataclass
class Pose2D:
    x: float = 0.0
    y: float = 0.0
    theta: float = 0.0


def normalize_angle(angle: float) -> float:
    """Angle in (-pi, pi]; headings are compared and published in this range."""
    angle = math.fmod(angle + math.pi, 2.0 * math.pi)
    if angle <= 0.0:
        angle += 2.0 * math.pi
    return angle - math.pi


def integrate_pose(pose: Pose2D, v: float, w: float, dt: float) -> Pose2D:
    """Exact unicycle integration over ``dt`` at constant (v, w): an arc, not a tangent step,
    so a full circle commanded in small steps closes on itself."""
    if abs(w) < 1e-9:
        return Pose2D(pose.x + v * dt * math.cos(pose.theta),
                      pose.y + v * dt * math.sin(pose.theta), pose.theta)
    theta2 = pose.theta + w * dt
    radius = v / w
    return Pose2D(pose.x + radius * (math.sin(theta2) - math.sin(pose.theta)),
                  pose.y - radius * (math.cos(theta2) - math.cos(pose.theta)),
                  normalize_angle(theta2))


def wheel_speeds(v: float, w: float) -> tuple[float, float]:
    """(left, right) wheel angular speeds in rad/s for body velocity (v m/s, w rad/s)."""
    left = (v - w * WHEEL_BASE / 2.0) / WHEEL_RADIUS
    right = (v + w * WHEEL_BASE / 2.0) / WHEEL_RADIUS
    return left, right


def tick_delta(previous: int, current: int) -> int:
    """Signed tick difference between two uint16 encoder readings, across the wrap."""
    delta = (current - previous) % TICKS_WRAP
    if delta >= TICKS_WRAP // 2:
        delta -= TICKS_WRAP
    return delta


def odometry_step(pose: Pose2D, d_left_ticks: int, d_right_ticks: int,
                  heading: float | None = None) -> tuple[Pose2D, float, float]:
    """Advance ``pose`` by one encoder delta; returns (pose, distance, rotation).

    With ``heading`` (the gyro's absolute yaw, kobuki's ``use_imu_heading``) the rotation
    comes from the gyro and only the distance from the wheels: wheel slip corrupts the
    heading far more than the distance.
    """
    dl = d_left_ticks * TICK_TO_RAD * WHEEL_RADIUS
    dr = d_right_ticks * TICK_TO_RAD * WHEEL_RADIUS
    distance = (dl + dr) / 2.0
    rotation = (dr - dl) / WHEEL_BASE
    if heading is not None:
        rotation = normalize_angle(heading - pose.theta)
    mid = pose.theta + rotation / 2.0
    new_pose = Pose2D(pose.x + distance * math.cos(mid), pose.y + distance * math.sin(mid),
                      normalize_angle(pose.theta + rotation))
    return new_pose, distance, rotation


def yaw_to_quaternion(yaw: float) -> tuple[float, float, float, float]:
    """(x, y, z, w) of a rotation about z."""
    return 0.0, 0.0, math.sin(yaw / 2.0), math.cos(yaw / 2.0)


def quaternion_to_yaw(x: float, y: float, z: float, w: float) -> float:
    return math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))


@dataclass
class BatteryModel:
    """Voltage falls slowly at idle and faster while the motors draw current."""

    capacity: float = 16.5
    low: float = 14.0
    dangerous: float = 13.2
    voltage: float = 16.5
    idle_drain: float = 0.0005    # V/s
    motor_drain: float = 0.002    # V/s at full (1 rad/s-ish) effort

    def drain(self, dt: float, effort: float) -> None:
        self.voltage = max(0.0, self.voltage - dt * (self.idle_drain + self.motor_drain * effort))

    @property
    def percent(self) -> float:
        span = self.capacity - self.dangerous
        if span <= 0:
            return 0.0
        return max(0.0, min(100.0, 100.0 * (self.voltage - self.dangerous) / span))

    def status(self) -> tuple[int, str]:
        if self.voltage <= self.dangerous:
            return ERROR, "Critical Power"
        if self.voltage <= self.low:
            return WARN, "Low Power"
        return OK, "Normal"


@dataclass
class DiagnosticItem:
    """One diagnostic_msgs/DiagnosticStatus, without the message class."""

    level: int
    name: str
    message: str
    hardware_id: str = "Kobuki"
    values: list[tuple[str, str]] = field(default_factory=list)


@dataclass
class KobukiBase:
    """The simulated robot: integrates the last velocity command into true motion.

    ``cmd_vel_timeout``: a command older than this stops the base, like the real driver's
    watchdog, so a crashed teleop never leaves the robot driving.
    """

    cmd_vel_timeout: float = 0.6
    use_imu_heading: bool = True
    gyro_noise: float = 0.0         # rad/s standard deviation added to the gyro rate
    battery: BatteryModel = field(default_factory=BatteryModel)
    seed: int | None = None

    true_pose: Pose2D = field(default_factory=Pose2D)
    odom_pose: Pose2D = field(default_factory=Pose2D)
    gyro_heading: float = 0.0
    left_wheel: float = 0.0          # accumulated wheel angle, rad
    right_wheel: float = 0.0
    left_encoder: int = 0
    right_encoder: int = 0
    v: float = 0.0                   # velocity actually executed
    w: float = 0.0
    gyro_rate: float = 0.0
    motors_enabled: bool = True
    digital_outputs: tuple[int, int, int, int] = (0, 0, 0, 0)
    _command: tuple[float, float] = (0.0, 0.0)
    _command_time: float | None = None
    _rng: random.Random = field(init=False, repr=False)

    def __post_init__(self) -> None:
        self._rng = random.Random(self.seed)

    def command(self, v: float, w: float, now: float) -> None:
        self._command = (v, w)
        self._command_time = now

    def active_command(self, now: float) -> tuple[float, float]:
        """The command in force at ``now``: zero when none is fresh or the motors are off."""
        if not self.motors_enabled or self._command_time is None:
            return 0.0, 0.0
        if now - self._command_time > self.cmd_vel_timeout:
            return 0.0, 0.0
        return self._command

    def step(self, now: float, dt: float) -> None:
        """Advance the simulation by ``dt`` seconds ending at ``now``."""
        if dt <= 0:
            return
        self.v, self.w = self.active_command(now)
        self.true_pose = integrate_pose(self.true_pose, self.v, self.w, dt)
        wl, wr = wheel_speeds(self.v, self.w)
        self.left_wheel += wl * dt
        self.right_wheel += wr * dt
        new_left = int(round(self.left_wheel / TICK_TO_RAD)) % TICKS_WRAP
        new_right = int(round(self.right_wheel / TICK_TO_RAD)) % TICKS_WRAP
        d_left = tick_delta(self.left_encoder, new_left)
        d_right = tick_delta(self.right_encoder, new_right)
        self.left_encoder, self.right_encoder = new_left, new_right
        noise = self._rng.gauss(0.0, self.gyro_noise) if self.gyro_noise > 0 else 0.0
        self.gyro_rate = self.w + noise
        self.gyro_heading = normalize_angle(self.gyro_heading + self.gyro_rate * dt)
        heading = self.gyro_heading if self.use_imu_heading else None
        self.odom_pose, _, _ = odometry_step(self.odom_pose, d_left, d_right, heading)
        self.battery.drain(dt, abs(wl) + abs(wr))

    def diagnostics(self, prefix: str) -> list[DiagnosticItem]:
        """The base's diagnostic tasks, named ``"<prefix>: <task>"`` like a C++ diagnostic
        updater running inside the nodelet manager ``prefix`` (hence the aggregator's
        ``remove_prefix``)."""
        def name(task: str) -> str:
            return f"{prefix}: {task}" if prefix else task

        level, message = self.battery.status()
        wl, wr = wheel_speeds(self.v, self.w)
        items = [
            DiagnosticItem(level, name("Battery"), message, values=[
                ("Voltage (V)", f"{self.battery.voltage:.2f}"),
                ("Percent", f"{self.battery.percent:.1f}"),
                ("Charging State", "Not Charging")]),
            DiagnosticItem(OK, name("Watchdog"), "Alive"),
            DiagnosticItem(OK if self.motors_enabled else WARN, name("Motor State"),
                           "Motors Enabled" if self.motors_enabled else "Motors Disabled"),
            DiagnosticItem(OK, name("Cliff Sensor"), "All right",
                           values=[("Left", "0"), ("Center", "0"), ("Right", "0")]),
            DiagnosticItem(OK, name("Wall Sensor"), "All right",
                           values=[("Left", "False"), ("Center", "False"), ("Right", "False")]),
            DiagnosticItem(OK, name("Wheel Drop"), "All right",
                           values=[("Left", "False"), ("Right", "False")]),
            DiagnosticItem(OK, name("Motor Current"), "All right", values=[
                ("Left", str(int(abs(wl) * 10))), ("Right", str(int(abs(wr) * 10)))]),
            DiagnosticItem(OK, name("Gyro Sensor"), "Heading (deg)", values=[
                ("Heading", f"{math.degrees(self.gyro_heading):.2f}")]),
            DiagnosticItem(OK, name("Digital Input"), "[0, 0, 0, 0]"),
            DiagnosticItem(OK, name("Analog Input"), "[0, 0, 0, 0]"),
            DiagnosticItem(OK, name("External Power"),
                           "[" + ", ".join(str(v) for v in self.digital_outputs) + "]"),
        ]
        return items
