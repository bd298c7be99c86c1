"""A simulated planar laser scanner, and the :class:`Scan` it gives.

:class:`Lidar` scans for one ``lidar2d`` sensor of a robot's descriptor
(:class:`~bt_manip.sensing.sensors.LidarSpec`) at the robot's true pose in the world: the
beams lie in the horizontal plane at the sensor's height, fan out from its heading, and stop
at the first wall, piece of furniture, movable object (a held one included), crate added
while the world runs, or part of a robot (this one included) they meet in that plane
(:mod:`bt_manip.sensing.scan_scene`, :mod:`bt_manip.sensing.raycast`). A shape that holds the
sensor's origin (the inside of its housing, the chassis it sits in) is never seen.

Readings, as a ROS driver gives them and AMCL reads them:

- a beam that meets nothing within ``range_m`` reads **exactly** ``range_max``: a "no return"
  (AMCL leaves such readings out; :attr:`Scan.no_return` marks them);
- with a generator passed, each other beam gets Gaussian noise of ``noise_m`` (clipped to
  ``0 .. range_max``; a reading pushed to ``range_max`` reads as no return) and, with
  ``dropout``, each beam is lost with that probability (a no return). The same generator
  state gives the same scan; without one the ranges are exact.
"""

from __future__ import annotations

import math
from collections.abc import Collection
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from bt_manip.geometry import compose_poses, quat_from_euler, rotation_matrix
from bt_manip.sensing.raycast import cast
from bt_manip.sensing.scan_scene import ScanScene
from bt_manip.sensing.sensors import LidarSpec

if TYPE_CHECKING:
    from bt_manip.sim.robot import Robot
    from bt_manip.sim.world import World

__all__ = ["Lidar", "Scan", "lidars_of"]


@dataclass(frozen=True)
class Scan:
    """One sweep of a planar laser (the fields of a ROS ``sensor_msgs/LaserScan``).

    Beam ``k`` points at ``angle_min + k * angle_increment`` (rad, counter-clockwise from the
    sensor's x axis) and reads ``ranges[k]`` (m); ``range_max`` means no return.
    """

    ranges: np.ndarray
    angle_min: float
    angle_increment: float
    range_max: float
    time: float
    """Sim time of the scan (s)."""
    sensor_pose: tuple[float, float, float]
    """The sensor in the robot's base frame: x, y (m) and yaw (rad)."""
    range_min: float = 0.0
    sensor: str = ""
    """The sensor's name in the descriptor."""
    true_pose: tuple[float, float, float] = (0.0, 0.0, 0.0)
    """The sensor's world pose (x, y, yaw) when it scanned: ground truth, for checks and
    displays, never for a localisation filter."""

    @property
    def angles(self) -> np.ndarray:
        """Each beam's angle (rad, sensor frame)."""
        return self.angle_min + self.angle_increment * np.arange(len(self.ranges))

    @property
    def no_return(self) -> np.ndarray:
        """True for the beams that met nothing (or were lost)."""
        return self.ranges >= self.range_max

    def points(self) -> np.ndarray:
        """The returns as points (n, 2) in the sensor frame (no-return beams left out)."""
        hit = ~self.no_return
        a = self.angles[hit]
        r = self.ranges[hit]
        return np.column_stack([r * np.cos(a), r * np.sin(a)])


class Lidar:
    """The laser ``spec`` of ``robot`` in ``world`` (see the module docstring).

    Args:
        world: the world scanned.
        robot: the robot carrying the laser.
        spec: one of the robot's declared sensors, by record or name (default: its first
            ``lidar2d``).
        rng: the generator of noise and dropouts; None gives exact ranges.
    """

    def __init__(
        self,
        world: World,
        robot: Robot,
        spec: LidarSpec | str | None = None,
        rng: np.random.Generator | None = None,
    ) -> None:
        self.world = world
        self.robot = robot
        self.spec = _find_spec(robot, spec)
        self.rng = rng
        self.scene = ScanScene(world)
        x, y, z = self.spec.xyz
        self._mount = ((x, y, z), quat_from_euler(self.spec.rpy))

    @property
    def period(self) -> float:
        """Seconds between scans (1 / ``rate_hz``)."""
        return 1.0 / self.spec.rate_hz

    def sensor_pose(self) -> tuple[np.ndarray, float]:
        """The sensor's origin (3,) and heading (rad) in the world, now."""
        link_pos, link_quat = self.robot.link_pose(self.spec.link)
        pos, quat = compose_poses((link_pos.tolist(), link_quat.tolist()), self._mount)
        r = rotation_matrix(quat)
        return np.asarray(pos, dtype=float), math.atan2(r[1, 0], r[0, 0])

    def scan(self, dropout: float = 0.0, rng: np.random.Generator | None = None) -> Scan:
        """A scan at the robot's true state now; ``dropout``: the probability of each beam to
        be lost (needs a generator); ``rng``: draw the noise and dropouts from this generator
        instead of the laser's own (a second reader of the same laser, whose draws leave the
        laser's own sequence as it was)."""
        if not 0.0 <= dropout <= 1.0:
            raise ValueError(f"dropout must be within 0..1, got {dropout}")
        rng = rng if rng is not None else self.rng
        if dropout > 0.0 and rng is None:
            raise ValueError("a dropout needs a random generator (Lidar(..., rng=...))")
        spec = self.spec
        origin, heading = self.sensor_pose()
        cut = self.scene.section(float(origin[2]))
        ranges = cast(origin[0], origin[1], heading, spec.angle_min, spec.angle_increment,
                      spec.beams, cut.segments, cut.circles)
        hit = ranges < spec.range_m
        if rng is not None:
            noise = rng.normal(0.0, 1.0, spec.beams) * spec.noise_m
            ranges = np.where(hit, np.clip(ranges + noise, 0.0, spec.range_m), ranges)
            if dropout > 0.0:
                ranges[rng.random(spec.beams) < dropout] = spec.range_m
        ranges = np.minimum(ranges, spec.range_m)
        return Scan(
            ranges=ranges,
            angle_min=spec.angle_min,
            angle_increment=spec.angle_increment,
            range_max=spec.range_m,
            time=self.world.time,
            sensor_pose=self._in_base(origin, heading),
            sensor=spec.name,
            true_pose=(float(origin[0]), float(origin[1]), heading),
        )

    def model_ranges(self, bodies: Collection[int]) -> np.ndarray:
        """Exact ranges (``beams``,) from the sensor now to ``bodies`` alone (``inf`` where a
        beam misses them): where the robot's own model, and what it holds, would stop each
        beam. A self filter compares a scan with these to leave out the returns from the robot
        itself (what the robot knows of its own shape, joints and grasp, not of the world)."""
        spec = self.spec
        origin, heading = self.sensor_pose()
        cut = self.scene.bodies_section(float(origin[2]), bodies)
        return cast(origin[0], origin[1], heading, spec.angle_min, spec.angle_increment,
                    spec.beams, cut.segments, cut.circles)

    def _in_base(self, origin: np.ndarray, heading: float) -> tuple[float, float, float]:
        bx, by, byaw = self.robot.base_pose2d()
        c, s = math.cos(byaw), math.sin(byaw)
        dx, dy = float(origin[0]) - bx, float(origin[1]) - by
        yaw = math.atan2(math.sin(heading - byaw), math.cos(heading - byaw))
        return c * dx + s * dy, -s * dx + c * dy, yaw


def lidars_of(
    world: World, robot: Robot, rng: np.random.Generator | None = None
) -> list[Lidar]:
    """A :class:`Lidar` for each laser declared in the robot's descriptor (sharing ``rng``)."""
    return [Lidar(world, robot, spec, rng) for spec in robot.description.sensors]


def _find_spec(robot: Robot, spec: LidarSpec | str | None) -> LidarSpec:
    if isinstance(spec, LidarSpec):
        return spec
    sensors = robot.description.sensors
    for s in sensors:
        if spec is None or s.name == spec:
            return s
    known = ", ".join(s.name for s in sensors) or "none"
    what = f"no sensor '{spec}'" if spec is not None else "no lidar2d sensor"
    raise KeyError(f"{robot.name} has {what}; sensors: {known}")
