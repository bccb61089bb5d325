"""A planar extended Kalman filter fusing wheel odometry and an IMU heading, pure.

State ``(x, y, yaw)`` with a 3x3 covariance. Like robot_pose_ekf, odometry is used as a
RELATIVE measurement: each odom message contributes only the motion since the previous one,
expressed in the robot's frame, so the filter never inherits the odometry's accumulated
drift in absolute terms; it only inherits the (growing) uncertainty, which the IMU heading
then pins down. The IMU yaw is an absolute measurement relative to its first reading (the
filter starts aligned with the odometry), which is how a gyro heading is usable at all.

Process noise grows with the distance and rotation travelled (a wheel slips per metre, not
per second), so a robot standing still does not become uncertain.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

Matrix = list[list[float]]


def normalize_angle(angle: float) -> float:
    return math.atan2(math.sin(angle), math.cos(angle))


def mat_mul(a: Matrix, b: Matrix) -> Matrix:
    return [[sum(a[i][k] * b[k][j] for k in range(len(b))) for j in range(len(b[0]))]
            for i in range(len(a))]


def transpose(a: Matrix) -> Matrix:
    return [list(row) for row in zip(*a, strict=False)]


def mat_add(a: Matrix, b: Matrix) -> Matrix:
    return [[x + y for x, y in zip(ra, rb, strict=False)] for ra, rb in zip(a, b, strict=False)]


def diag(*values: float) -> Matrix:
    n = len(values)
    return [[values[i] if i == j else 0.0 for j in range(n)] for i in range(n)]


def relative_motion(prev: tuple[float, float, float],
                    curr: tuple[float, float, float]) -> tuple[float, float, float]:
    """The motion from pose ``prev`` to ``curr`` expressed in ``prev``'s own frame."""
    dx, dy = curr[0] - prev[0], curr[1] - prev[1]
    c, s = math.cos(prev[2]), math.sin(prev[2])
    return c * dx + s * dy, -s * dx + c * dy, normalize_angle(curr[2] - prev[2])


@dataclass
class NoiseModel:
    """Standard deviations per unit of motion, plus a floor so the covariance stays positive."""

    xy_per_m: float = 0.05          # m of position error per m travelled
    yaw_per_rad: float = 0.05       # rad of heading error per rad turned
    yaw_per_m: float = 0.02         # rad of heading error per m travelled (wheel slip)
    floor: float = 1e-6             # variance added every prediction


@dataclass
class PlanarEKF:
    x: float = 0.0
    y: float = 0.0
    yaw: float = 0.0
    P: Matrix = field(default_factory=lambda: diag(1e-6, 1e-6, 1e-6))
    noise: NoiseModel = field(default_factory=NoiseModel)
    imu_default_variance: float = 0.01
    _last_odom: tuple[float, float, float] | None = None
    _imu_offset: float | None = None

    @property
    def initialized(self) -> bool:
        return self._last_odom is not None

    def state(self) -> tuple[float, float, float]:
        return self.x, self.y, self.yaw

    def predict(self, dx: float, dy: float, dyaw: float) -> None:
        """Apply a body-frame motion (dx forward, dy left, dyaw) with its noise."""
        c, s = math.cos(self.yaw), math.sin(self.yaw)
        self.x += c * dx - s * dy
        self.y += s * dx + c * dy
        self.yaw = normalize_angle(self.yaw + dyaw)
        F = [[1.0, 0.0, -s * dx - c * dy],
             [0.0, 1.0, c * dx - s * dy],
             [0.0, 0.0, 1.0]]
        dist = math.hypot(dx, dy)
        n = self.noise
        sxy = n.xy_per_m * dist
        syaw = n.yaw_per_rad * abs(dyaw) + n.yaw_per_m * dist
        Q = diag(sxy * sxy + n.floor, sxy * sxy + n.floor, syaw * syaw + n.floor)
        self.P = mat_add(mat_mul(mat_mul(F, self.P), transpose(F)), Q)

    def add_odometry(self, pose: tuple[float, float, float]) -> None:
        """An absolute odometry pose; only its change since the last one is used."""
        if self._last_odom is None:
            # the first odometry defines the filter's frame: start where the odometry is
            self.x, self.y, self.yaw = pose
            self._last_odom = pose
            return
        motion = relative_motion(self._last_odom, pose)
        self._last_odom = pose
        self.predict(*motion)

    def update_yaw(self, measured_yaw: float, variance: float) -> None:
        """A direct heading measurement (H = [0 0 1])."""
        innovation = normalize_angle(measured_yaw - self.yaw)
        S = self.P[2][2] + variance
        if S <= 0:
            return
        K = [self.P[i][2] / S for i in range(3)]
        self.x += K[0] * innovation
        self.y += K[1] * innovation
        self.yaw = normalize_angle(self.yaw + K[2] * innovation)
        row = list(self.P[2])
        self.P = [[self.P[i][j] - K[i] * row[j] for j in range(3)] for i in range(3)]

    def add_imu(self, imu_yaw: float, variance: float | None = None) -> None:
        """An IMU heading; its first value is aligned with the filter's heading then."""
        if not self.initialized:
            return  # no frame to align to yet
        if self._imu_offset is None:
            self._imu_offset = normalize_angle(self.yaw - imu_yaw)
            return
        if variance is None or not (0.0 < variance < 1e3):
            variance = self.imu_default_variance
        self.update_yaw(normalize_angle(imu_yaw + self._imu_offset), variance)

    def covariance_6x6(self, unobserved: float = 1e6) -> list[float]:
        """Row-major 6x6 (x, y, z, roll, pitch, yaw) for geometry_msgs/PoseWithCovariance."""
        idx = {0: 0, 1: 1, 5: 2}
        out = [0.0] * 36
        for r in range(6):
            for c in range(6):
                if r in idx and c in idx:
                    out[r * 6 + c] = self.P[idx[r]][idx[c]]
                elif r == c:
                    out[r * 6 + c] = unobserved
        return out
