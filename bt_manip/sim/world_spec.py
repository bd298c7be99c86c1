"""The world file's records: what a checked world file says, as dataclasses.

:mod:`bt_manip.sim.world_reader` reads a world file (YAML) into these records, with every
problem's file and line; :mod:`bt_manip.sim.randomize` varies their poses per seed; the runtime
:class:`~bt_manip.sim.world.World` builds a simulation from them. This module reads no file and
draws no random number.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, NamedTuple

COLOURS: dict[str, tuple[float, float, float, float]] = {
    "white": (0.95, 0.95, 0.95, 1.0),
    "grey": (0.6, 0.6, 0.6, 1.0),
    "dark_grey": (0.3, 0.3, 0.3, 1.0),
    "black": (0.1, 0.1, 0.1, 1.0),
    "red": (0.85, 0.15, 0.15, 1.0),
    "green": (0.2, 0.7, 0.25, 1.0),
    "blue": (0.2, 0.35, 0.85, 1.0),
    "yellow": (0.95, 0.8, 0.1, 1.0),
    "orange": (0.95, 0.55, 0.1, 1.0),
    "brown": (0.55, 0.35, 0.2, 1.0),
    "wood": (0.7, 0.52, 0.33, 1.0),
    "beige": (0.87, 0.8, 0.66, 1.0),
    "purple": (0.5, 0.25, 0.65, 1.0),
    "cyan": (0.2, 0.75, 0.8, 1.0),
}


class Pose2D(NamedTuple):
    """A planar pose: position in metres, heading in radians."""

    x: float
    y: float
    yaw: float


class _SharedByCopies:
    """A frozen record of numbers and text only: a deep copy of a spec shares it (a copy
    would be the same value)."""

    def __deepcopy__(self, memo: dict[int, Any]) -> _SharedByCopies:
        return self


@dataclass(frozen=True)
class Pose3D(_SharedByCopies):
    """A full pose: position and quaternion (x, y, z, w)."""

    xyz: tuple[float, float, float]
    quat: tuple[float, float, float, float] = (0.0, 0.0, 0.0, 1.0)


@dataclass(frozen=True)
class Range2D(_SharedByCopies):
    """Uniform offsets sampled per seed: each is (low, high)."""

    x: tuple[float, float] = (0.0, 0.0)
    y: tuple[float, float] = (0.0, 0.0)
    yaw: tuple[float, float] = (0.0, 0.0)

    def is_zero(self) -> bool:
        return self.x == (0.0, 0.0) and self.y == (0.0, 0.0) and self.yaw == (0.0, 0.0)


@dataclass(frozen=True)
class Part(_SharedByCopies):
    """One primitive: ``box`` (size = full extents), ``cylinder`` (radius, height) or ``sphere``."""

    shape: str
    size: tuple[float, float, float]
    xyz: tuple[float, float, float] = (0.0, 0.0, 0.0)
    rpy: tuple[float, float, float] = (0.0, 0.0, 0.0)
    colour: tuple[float, float, float, float] | None = None

    def bottom(self) -> float:
        """Lowest z of the part in its body frame (rotation about z only is exact)."""
        half = self.size[2] / 2.0 if self.shape != "sphere" else self.size[0]
        return self.xyz[2] - half


@dataclass
class DoorSpec:
    at: float
    width: float
    line: int


@dataclass
class WallSpec:
    name: str
    start: tuple[float, float]
    end: tuple[float, float]
    thickness: float
    height: float
    colour: tuple[float, float, float, float]
    doors: list[DoorSpec]
    line: int

    @property
    def length(self) -> float:
        return math.dist(self.start, self.end)


@dataclass
class BodySpec:
    """A static piece of furniture or a movable object."""

    name: str
    movable: bool
    parts: list[Part]
    urdf: Path | None
    pose: Pose3D
    planar: bool
    mass: float
    friction: float
    colour: tuple[float, float, float, float]
    randomize: Range2D
    line: int
    scale: float = 1.0


@dataclass(frozen=True)
class BatterySpec(_SharedByCopies):
    """A robot's simulated battery: its charge (0..1) and voltage at the start, and how much
    charge it loses per second of sim time (the voltage stays as given)."""

    percentage: float = 1.0
    voltage: float = 12.0
    drain: float = 0.0

    def percentage_at(self, t: float) -> float:
        """The charge left after ``t`` seconds of sim time (never below 0)."""
        return max(0.0, self.percentage - self.drain * max(0.0, t))


@dataclass
class RobotSpec:
    name: str
    description: str
    description_path: Path
    pose: Pose2D
    arm_state: str | None
    randomize: Range2D
    line: int
    battery: BatterySpec = field(default_factory=BatterySpec)


@dataclass
class PhysicsSpec:
    rate_hz: float = 240.0
    gravity: tuple[float, float, float] = (0.0, 0.0, -9.81)
    solver_iterations: int = 50
    solver_tolerance: float | None = None
    """m/s: the constraint solver stops iterating once a sweep changes no constraint's velocity
    by more than this (PyBullet's solverResidualThreshold is its square); None keeps PyBullet's
    own threshold (1e-7, about 0.3 mm/s). A looser one makes steps cheaper and contacts less
    exact: 0.01 saves about 15 % of a step and changes which way a touching crate goes."""
    ground_friction: float = 1.0


@dataclass(frozen=True)
class GroupSpec:
    """One ``groups:`` entry, checked: its members, pivot, fixed move and random ranges (see
    :mod:`bt_manip.sim.groups`)."""

    name: str
    members: tuple[str, ...]
    origin: tuple[float, float]
    move: tuple[float, float, float]
    randomize: Range2D
    line: int


@dataclass
class WorldSpec:
    """A parsed, checked world file."""

    path: Path
    name: str
    physics: PhysicsSpec
    walls: list[WallSpec] = field(default_factory=list)
    furniture: list[BodySpec] = field(default_factory=list)
    objects: list[BodySpec] = field(default_factory=list)
    models: list[BodySpec] = field(default_factory=list)
    """Movable objects declared but not spawned: trees add them with SpawnModel."""
    robots: list[RobotSpec] = field(default_factory=list)
    poses: dict[str, Pose2D] = field(default_factory=dict)
    pose_lines: dict[str, int] = field(default_factory=dict)
    groups: list[GroupSpec] = field(default_factory=list)
    """Entities moved together by one rigid motion (``groups:``)."""
    route_graph: Path | None = None
    """A route graph in Nav2's GeoJSON format for ComputeRoute (None: one is generated)."""
    localization: LocalizationSpec | None = None
    """The ``localization:`` section: a run localises its robot (None: only with
    ``--localize``, with the defaults)."""

    def names_by_kind(self) -> dict[str, set[str]]:
        """What a tree may name in this world, by kind: ``object`` (movable objects and
        models), ``body`` (those, furniture and walls), ``pose`` (named poses), ``robot``."""
        movable = {b.name for b in [*self.objects, *self.models]}
        return {
            "object": movable,
            "body": movable | {b.name for b in self.furniture} | {w.name for w in self.walls},
            "pose": set(self.poses),
            "robot": {r.name for r in self.robots},
        }


WORLD_SCHEMA_VERSION = 1
"""The world format this bt-manip reads (``schema_version`` of a world file; absent means 1)."""


DEFAULT_INITIAL_SIGMAS = (0.1, 0.1, 0.1)
"""Standard deviations (m, m, rad) of the initial pose a run's filter starts from, unless the
world's ``localization:`` section gives its own (an operator's initial pose is good to about
10 cm)."""


@dataclass(frozen=True)
class LocalizationSpec(_SharedByCopies):
    """A world file's ``localization:`` section (every key optional): how a run with
    ``--localize`` localises its robot. None leaves the filter's default."""

    min_particles: int | None = None
    max_particles: int | None = None
    initial_pose: Pose2D | None = None
    """Where the filter starts (map frame); None: the robot's start pose."""
    initial_sigmas: tuple[float, float, float] = DEFAULT_INITIAL_SIGMAS
    update_min_d: float | None = None
    update_min_a: float | None = None
    line: int = 0
