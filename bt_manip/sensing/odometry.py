"""Wheel odometry: the base's pose integrated from what its wheels (or virtual joints) did.

:class:`WheelOdometry` reads the wheel joint angles each time :meth:`WheelOdometry.update` is
called (every tick, or every physics step) and integrates their differences through the base's
kinematics, so a wheel that slips (spinning against a wall, dragged sideways) is counted as it
turned, and the odometry parts from the truth as a real one does:

- skid-steer / differential bases: each side's travel is the wheel radius times the mean angle
  change of its wheels; the base moves ``ds = (sl + sr) / 2`` and turns ``dyaw = (sr - sl) / B``
  with ``B`` the descriptor's effective ``track_width`` (measured turning the Husky on the
  spot; a skid-steer turns less than its wheel separation says). Each step is integrated as an
  arc (constant speed and turn rate over the step).
- holonomic bases: the change of the virtual x, y and yaw joints, turned into the base frame.

The odometry frame starts where the base is when the odometry is made: the first reading is
(0, 0, 0), as a ROS ``odom`` frame starts.

Noise (:class:`OdometryNoise`, drawn from a seeded generator passed in) grows with the motion,
as AMCL's odometry model has it (its ``alpha`` parameters), but with variances proportional to
the distance and angle moved rather than to their squares, so that the drift after a given
motion does not depend on how often the odometry is updated: after travelling ``d`` metres
and turning ``a`` radians, the travel error has a standard deviation ``k * sqrt(d)`` and the
heading error ``sqrt(k_rot^2 * a + k_drift^2 * d)``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from bt_manip.sim import pybullet_queries as pbq

if TYPE_CHECKING:
    from bt_manip.sim.robot import Robot

__all__ = ["Odometry", "OdometryNoise", "WheelOdometry"]


@dataclass(frozen=True)
class Odometry:
    """One odometry reading: the base's pose in the odometry frame, and when."""

    x: float
    y: float
    yaw: float
    time: float


@dataclass(frozen=True)
class OdometryNoise:
    """How much odometry errs (see the module docstring); zero everywhere means exact."""

    k: float = 0.0
    """Travel error (m) after 1 m travelled (its variance grows with the distance)."""
    k_rot: float = 0.0
    """Heading error (rad) after turning 1 rad."""
    k_drift: float = 0.0
    """Heading error (rad) after 1 m travelled straight."""

    def __post_init__(self) -> None:
        for name in ("k", "k_rot", "k_drift"):
            value = getattr(self, name)
            if not (math.isfinite(value) and 0.0 <= value <= 1.0):
                raise ValueError(f"OdometryNoise.{name} must be within 0..1, got {value}")

    @property
    def is_zero(self) -> bool:
        return self.k == 0.0 and self.k_rot == 0.0 and self.k_drift == 0.0


class WheelOdometry:
    """Odometry of ``robot`` (a skid-steer or holonomic base), integrated at each
    :meth:`update`.

    Args:
        robot: the robot whose wheels are read.
        noise: the error model (none: exact integration).
        rng: the generator the errors are drawn from (needed with noise).
        track_width: the effective track width (m) of a wheeled base; default the
            descriptor's.
        time: the sim time of the first reading.
    """

    def __init__(
        self,
        robot: Robot,
        noise: OdometryNoise | None = None,
        rng: np.random.Generator | None = None,
        track_width: float | None = None,
        time: float = 0.0,
    ) -> None:
        if not (robot.has_wheels or robot.is_holonomic):
            raise ValueError(f"{robot.name} has a fixed base: no odometry")
        if noise is not None and not noise.is_zero and rng is None:
            raise ValueError("odometry noise needs a random generator (rng=...)")
        self.robot = robot
        self.noise = noise if noise is not None and not noise.is_zero else None
        self.rng = rng
        base = robot.description.base
        self.track_width = base.track_width if track_width is None else float(track_width)
        if robot.has_wheels and not self.track_width > 0.0:
            raise ValueError(f"track_width must be > 0, got {self.track_width}")
        self.radius = base.wheel_radius
        self.pivot_offset = base.pivot_offset
        self._joints = (robot.base_joint_ids if robot.is_holonomic
                        else robot.wheel_ids_left + robot.wheel_ids_right)
        self._last = self._read()
        self.x = self.y = self.yaw = 0.0
        self.time = time
        self.distance = 0.0
        """Metres travelled so far (as the wheels count them)."""

    def _read(self) -> list[float]:
        return pbq.joint_motion(self.robot.client, self.robot.body, self._joints)[0]

    def reading(self) -> Odometry:
        """The last reading."""
        return Odometry(self.x, self.y, self.yaw, self.time)

    def update(self, time: float) -> Odometry:
        """Integrate the wheels' motion since the last update; the new reading."""
        now = self._read()
        before, self._last = self._last, now
        delta = [a - b for a, b in zip(now, before, strict=True)]
        if self.robot.is_holonomic:
            dx, dy, dyaw = delta
            # the virtual x and y joints move along the fixed root's axes; turned into the
            # base's frame by its heading there (the yaw joint) at the step's start
            c, s = math.cos(before[2]), math.sin(before[2])
            forward, left = c * dx + s * dy, -s * dx + c * dy
        else:
            n_left = len(self.robot.wheel_ids_left)
            left_angle = sum(delta[:n_left]) / n_left
            right_angle = sum(delta[n_left:]) / (len(delta) - n_left)
            sl, sr = self.radius * left_angle, self.radius * right_angle
            dyaw = (sr - sl) / self.track_width
            # a skid-steer turns about a point ``pivot_offset`` ahead of its frame: the frame
            # slides sideways as it turns
            forward, left = (sl + sr) / 2.0, -self.pivot_offset * dyaw
        forward, left, dyaw = self._noisy(forward, left, dyaw)
        self._integrate(forward, left, dyaw)
        self.distance += math.hypot(forward, left)
        self.time = time
        return self.reading()

    def _noisy(self, forward: float, left: float, dyaw: float) -> tuple[float, float, float]:
        if self.noise is None or self.rng is None:
            return forward, left, dyaw
        n = self.noise
        travel = math.hypot(forward, left)
        e_travel, e_yaw = self.rng.normal(0.0, 1.0, 2)
        scale = 1.0 + e_travel * n.k * math.sqrt(travel) / travel if travel > 0.0 else 1.0
        yaw_std = math.sqrt(n.k_rot**2 * abs(dyaw) + n.k_drift**2 * travel)
        return forward * scale, left * scale, dyaw + e_yaw * yaw_std

    def _integrate(self, forward: float, left: float, dyaw: float) -> None:
        """Move by (forward, left) in the base frame along an arc turning by ``dyaw``."""
        if abs(dyaw) > 1e-9:
            a = math.sin(dyaw) / dyaw
            b = (1.0 - math.cos(dyaw)) / dyaw
        else:
            a, b = 1.0 - dyaw * dyaw / 6.0, dyaw / 2.0
        # the step's chord in the frame at its start: the arc's motion turned by the turn
        fx, fy = a * forward - b * left, b * forward + a * left
        c, s = math.cos(self.yaw), math.sin(self.yaw)
        self.x += c * fx - s * fy
        self.y += s * fx + c * fy
        self.yaw = math.atan2(math.sin(self.yaw + dyaw), math.cos(self.yaw + dyaw))
