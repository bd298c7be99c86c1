"""Robot descriptors (``robots/<name>.yaml``): where they are found and what they say.

:class:`RobotDescription` is the checked content of a descriptor (format in ``robots/README.md``):
which URDF (or composition recipe), the base (``skid_steer``, ``holonomic`` or ``fixed``), the
arm joints in order, the gripper, the end-effector and grasp frames, named arm states and the
footprint, and the sensors mounted on it (:mod:`bt_manip.sensing.sensors`). Every name in it
is checked against the robot's URDF. This module is pure data:
nothing here touches PyBullet (:mod:`bt_manip.sim.robot` spawns and drives a described robot).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Collection, Mapping
from dataclasses import dataclass
from pathlib import Path
from types import MappingProxyType

import defusedxml.ElementTree as SafeET

from bt_manip.cache import Memo, bytes_key
from bt_manip.errors import InputError
from bt_manip.input_files import read_bounded
from bt_manip.sensing.sensors import LidarSpec, read_sensors
from bt_manip.sim.assets import data_root
from bt_manip.sim.compose import MAX_URDF_BYTES, Frame, Recipe, composed_urdf, parse_recipe
from bt_manip.sim.yaml_lines import FieldReader, LineDict, load_yaml

__all__ = [
    "ROBOTS_DIR",
    "ArmSpec",
    "BaseSpec",
    "Footprint",
    "GripperSpec",
    "RobotDescription",
    "descriptor_folders",
    "find_descriptor",
    "known_robots",
    "load_description",
]

# -- descriptors --------------------------------------------------------------------------------
ROBOTS_DIR = data_root() / "robots"
"""The shipped robot descriptors (the clone's ``robots/`` or the installed package data)."""
BASE_TYPES = ("skid_steer", "holonomic", "fixed")
TOP_KEYS = {
    "name",
    "urdf",
    "spawn_height",
    "base",
    "arm",
    "end_effector",
    "grasp_frame",
    "approach_axis",
    "gripper",
    "states",
    "footprint",
    "planning",
    "sensors",
}
PLANNING_KEYS = {"padding", "allowed_collisions", "srdf"}
ALLOWED_REASONS = ("default", "never", "user")
"""The reasons a pair of links may be listed under in ``planning.allowed_collisions``."""
DEFAULT_PADDING = 0.02
"""m the world's shapes grow by when an arm path is planned, unless the descriptor says."""
BASE_KEYS = {
    "type",
    "left_wheels",
    "right_wheels",
    "wheel_radius",
    "track_width",
    "max_wheel_speed",
    "wheel_max_torque",
    "wheel_friction",
    "wheel_spinning_friction",
    "wheel_rolling_friction",
    "wheel_axle_friction_scale",
    "pivot_offset",
}
HOLONOMIC_KEYS = {
    "type",
    "joints",
    "max_speed",
    "max_yaw_rate",
    "max_accel",
    "max_yaw_accel",
    "max_force",
    "max_torque",
}
ARM_KEYS = {
    "base_link", "joints", "velocity_limits", "acceleration_limits", "efforts", "position_gain",
}
ACCELERATION_PER_VELOCITY = 2.0
"""1/s: a joint without an acceleration limit reaches its velocity limit in half a second."""
GRIPPER_KEYS = {
    "kind",
    "width",
    "joints",
    "finger_links",
    "open",
    "closed",
    "max_force",
    "max_speed",
    "pad_friction",
}
FOOTPRINT_KEYS = {"length", "width", "x_offset", "radius"}
GRIPPER_KINDS = ("parallel", "revolute", "hand")
APPROACH_AXES: dict[str, tuple[float, float, float]] = {
    "z": (0.0, 0.0, 0.0),
    "-z": (math.pi, 0.0, 0.0),
    "x": (0.0, math.pi / 2.0, 0.0),
    "-x": (0.0, -math.pi / 2.0, 0.0),
    "y": (-math.pi / 2.0, 0.0, 0.0),
    "-y": (math.pi / 2.0, 0.0, 0.0),
}
"""Per approach axis of the grasp link, the rpy of the frame whose z axis is that axis (each
turn keeps one of the link's other axes)."""
APPROACH_FRAME = "approach_frame"
"""The frame added to a robot whose grasp link approaches along another axis than z."""


@dataclass(frozen=True)
class BaseSpec:
    """The mobile base: ``skid_steer`` (wheels left/right), ``holonomic`` (virtual planar
    joints x, y, yaw between a root fixed to the world and the base link) or ``fixed`` (welded
    to the world)."""

    type: str = "fixed"
    left_wheels: tuple[str, ...] = ()
    right_wheels: tuple[str, ...] = ()
    wheel_radius: float = 0.0
    track_width: float = 0.0
    """Effective track width (m) for skid-steer kinematics: yaw rate = (vr - vl) / track."""
    max_wheel_speed: float = 0.0
    wheel_max_torque: float = 0.0
    wheel_friction: float = 1.0
    wheel_spinning_friction: float = 0.0
    wheel_rolling_friction: float = 0.0
    wheel_axle_friction_scale: float = 1.0
    """Friction along the wheel axle relative to ``wheel_friction`` (< 1 lets a skid-steer turn)."""
    pivot_offset: float = 0.0
    """Where the base turns about when it turns on the spot (m ahead of its frame, measured)."""
    joints: tuple[str, ...] = ()
    """``holonomic``: the virtual planar joints (prismatic x, prismatic y, yaw), root first."""
    max_speed: float = 0.0
    """``holonomic``: largest planar speed (m/s)."""
    max_yaw_rate: float = 0.0
    """``holonomic``: largest yaw rate (rad/s)."""
    max_accel: float = 0.0
    """``holonomic``: planar acceleration limit of the path follower (m/s^2)."""
    max_yaw_accel: float = 0.0
    """``holonomic``: yaw acceleration limit of the path follower (rad/s^2)."""
    max_force: float = 0.0
    """``holonomic``: force (N) of each planar joint's motor: what the base pushes with."""
    max_torque: float = 0.0
    """``holonomic``: torque (N m) of the yaw joint's motor."""


@dataclass(frozen=True)
class ArmSpec:
    """The arm: chain root, joints in order, their speed and effort limits and lower/upper."""

    base_link: str
    joints: tuple[str, ...]
    velocity_limits: tuple[float, ...]
    efforts: tuple[float | None, ...]
    lower: tuple[float, ...] = ()
    upper: tuple[float, ...] = ()
    position_gain: float = 0.3
    acceleration_limits: tuple[float, ...] = ()
    """rad/s^2 (or m/s^2) per joint: how a planned path is timed."""


@dataclass(frozen=True)
class PlanningSpec:
    """The arm planner's settings (``planning``): padding, the allowed-collision matrix."""

    padding: float = DEFAULT_PADDING
    """m the world's shapes grow by when a path is planned (not for goals and straight moves)."""
    allowed: Mapping[str, frozenset[frozenset[str]]] | None = None
    """Pairs of links never checked against each other, by reason (``default``, ``never``,
    ``user``); None when the descriptor lists none (the planner then finds them itself)."""
    srdf: Path | None = None
    """An SRDF whose ``disable_collisions`` pairs are allowed too."""


@dataclass(frozen=True)
class GripperSpec:
    """The gripper: its finger joints and how an opening (m) maps onto them.

    ``parallel`` (the default): prismatic fingers, each joint the distance of one pad from the
    centre line, so the opening is the sum of the joints. ``revolute`` (jaws that turn) and
    ``hand`` (several fingers that curl): each joint goes from its ``closed`` to its ``open``
    position, all together, and the opening is read linearly between 0 (closed) and ``width``
    (the measured distance between the fingers when open). An arm without a gripper has no
    joints (``joints == ()``): its opening stays 0.
    """

    joints: tuple[str, ...]
    finger_links: tuple[str, ...]
    open: float
    closed: float
    max_force: float
    max_speed: float = 0.1
    pad_friction: float = 1.5
    kind: str = "parallel"
    opens: tuple[float, ...] = ()
    """Per joint, its open position (``open`` for every joint unless given one by one)."""
    closeds: tuple[float, ...] = ()
    """Per joint, its closed position."""
    width: float = 0.0
    """``revolute`` / ``hand``: the opening (m) when fully open."""

    @property
    def is_parallel(self) -> bool:
        return self.kind == "parallel"

    @property
    def open_positions(self) -> tuple[float, ...]:
        return self.opens or (self.open,) * len(self.joints)

    @property
    def closed_positions(self) -> tuple[float, ...]:
        return self.closeds or (self.closed,) * len(self.joints)

    @property
    def max_opening(self) -> float:
        """Distance between the pads when fully open (m)."""
        if not self.is_parallel:
            return self.width
        return max(self.open, self.closed) * len(self.joints)

    @property
    def min_opening(self) -> float:
        """Distance between the pads when closed on nothing (m)."""
        if not self.is_parallel:
            return 0.0
        return min(self.open, self.closed) * len(self.joints)

    @property
    def stroke_time(self) -> float:
        """Seconds the slowest finger joint takes from closed to open at ``max_speed``."""
        strokes = [abs(o - c) for o, c in zip(self.open_positions, self.closed_positions,
                                                 strict=True)]
        return max(strokes, default=0.0) / self.max_speed


@dataclass(frozen=True)
class Footprint:
    """Outline of the base for navigation: a rectangle (length x width) or a circle (radius).

    The rectangle is centred ``x_offset`` ahead of the root link frame.
    """

    length: float = 0.0
    width: float = 0.0
    x_offset: float = 0.0
    radius: float = 0.0

    @property
    def is_circle(self) -> bool:
        return self.radius > 0.0

    @property
    def circumradius(self) -> float:
        """Radius of the smallest circle around the root frame containing the footprint."""
        if self.is_circle:
            return self.radius
        return math.hypot(abs(self.x_offset) + self.length / 2.0, self.width / 2.0)


@dataclass(frozen=True)
class RobotDescription:
    """A checked robot descriptor (``robots/<name>.yaml``)."""

    name: str
    path: Path
    urdf: Path | Recipe
    base: BaseSpec
    arm: ArmSpec
    gripper: GripperSpec
    end_effector: str
    grasp_frame: str
    """The frame placed by MoveToPose and the grasp planners: z is the approach direction. It
    is the URDF's grasp link itself, or :data:`APPROACH_FRAME` added on it (``approach_axis``)."""
    states: dict[str, tuple[float, ...]]
    footprint: Footprint
    spawn_height: float = 0.0
    approach_axis: str = "z"
    """The axis of ``grasp_link`` along which the gripper approaches an object."""
    grasp_link: str = ""
    """The grasp frame as the descriptor names it (a link of the URDF)."""
    planning: PlanningSpec = PlanningSpec()
    """The arm planner's settings."""
    sensors: tuple[LidarSpec, ...] = ()
    """The sensors declared in ``sensors:`` (none by default)."""

    @classmethod
    def load(cls, name_or_path: str | Path) -> RobotDescription:
        """Read ``robots/<name>.yaml`` (or a path to a descriptor) and check it.

        Raises :class:`~bt_manip.errors.InputError` naming the file, line and key of every
        problem, including names that do not exist in the robot's URDF.
        """
        return load_description(name_or_path)

    def state(self, name: str) -> tuple[float, ...]:
        """Arm joint positions of the named state (``home``, ``tuck``, ...)."""
        try:
            return self.states[name]
        except KeyError:
            raise KeyError(
                f"{self.name} has no arm state '{name}'; states: {', '.join(self.states)}"
            ) from None

    @property
    def urdf_path(self) -> Path:
        """The URDF PyBullet and Pinocchio load (composed and cached if needed)."""
        return composed_urdf(self)


def descriptor_folders(near: Path | None = None) -> list[Path]:
    """Folders searched for a descriptor named without a path, first match wins.

    With ``near`` (the folder of a world file): its ``robots/`` folder, the ``robots/`` folder
    beside it, then the shipped ``robots/``; without: the shipped ``robots/`` only.
    """
    if near is None:
        return [ROBOTS_DIR]
    return [near / "robots", near.parent / "robots", ROBOTS_DIR]


def find_descriptor(name_or_path: str | Path, near: Path | None = None) -> Path | None:
    """The descriptor file a robot name or a descriptor path refers to, or None if none exists.

    A name ending in ``.yaml``/``.yml`` is a path (relative to ``near`` when given); any other
    name is looked up as ``<name>.yaml`` in :func:`descriptor_folders`. Without ``near``, an
    existing file is taken as a path whatever its suffix. Paths found for a world (``near``
    given) are resolved; without ``near`` they are returned as named.
    """
    p = Path(name_or_path)
    if p.suffix in (".yaml", ".yml") or (near is None and p.is_file()):
        if near is not None:
            p = (near / p).resolve()  # an absolute p stays itself
        return p if p.is_file() else None
    for folder in descriptor_folders(near):
        candidate = folder / f"{name_or_path}.yaml"
        if candidate.is_file():
            return candidate.resolve() if near is not None else candidate
    return None


def known_robots(near: Path | None = None) -> list[str]:
    """Names of the robot descriptors found in :func:`descriptor_folders`."""
    names: set[str] = set()
    for folder in descriptor_folders(near):
        if folder.is_dir():
            names.update(p.stem for p in folder.glob("*.yaml"))
    return sorted(names)


class _Fields(FieldReader):
    """The field readers of YAML input, plus the sections of a descriptor."""

    def section(self, d: LineDict, key: str, allowed: set[str], required: bool = True) -> LineDict:
        value = d.get(key)
        if value is None and not required:
            return _empty(d.line_of(key))
        if not isinstance(value, LineDict):
            self.fail(d.line_of(key), f"'{key}' must be a mapping")
            return _empty(d.line_of(key))
        self.unknown_keys(value, allowed, key)
        return value

    def real(
        self,
        d: LineDict,
        key: str,
        where: str,
        default: float | None = None,
        minimum: float | None = None,
        positive: bool = False,
    ) -> float:
        """Like :meth:`number`, 0.0 when the value is refused (the problem is recorded)."""
        value = self.number(d, key, where, default, positive=positive, minimum=minimum)
        return 0.0 if value is None else value


def _empty(line: int) -> LineDict:
    out = LineDict()
    out.line = line
    out.key_lines = {}
    return out


def load_description(name_or_path: str | Path) -> RobotDescription:
    """Read and check a robot descriptor; see :meth:`RobotDescription.load`."""
    path = find_descriptor(name_or_path)
    if path is None:
        p = Path(name_or_path)
        missing = p if p.suffix in (".yaml", ".yml") else ROBOTS_DIR / f"{name_or_path}.yaml"
        known = ", ".join(known_robots()) or "none"
        raise InputError.single(
            str(missing), None, f"no robot descriptor '{name_or_path}'; known robots: {known}"
        )
    data = load_yaml(path)
    f = _Fields(path)
    if not isinstance(data, LineDict):
        raise InputError.single(str(path), 1, "a robot descriptor must be a YAML mapping")
    f.unknown_keys(data, TOP_KEYS, "the descriptor")
    name = f.text(data, "name", "descriptor", default=path.stem)
    urdf = _parse_urdf_source(f, data, path)

    raw_base = data.get("base")
    holonomic = isinstance(raw_base, dict) and raw_base.get("type") == "holonomic"
    b = f.section(data, "base", HOLONOMIC_KEYS if holonomic else BASE_KEYS)
    base_type = b.get("type", "fixed")
    if base_type not in BASE_TYPES:
        f.fail(
            b.line_of("type"),
            f"base.type must be one of {', '.join(BASE_TYPES)}, got {base_type!r}",
        )
    if base_type == "skid_steer":
        base = BaseSpec(
            "skid_steer",
            f.names(b, "left_wheels", "base"),
            f.names(b, "right_wheels", "base"),
            f.real(b, "wheel_radius", "base", positive=True),
            f.real(b, "track_width", "base", positive=True),
            f.real(b, "max_wheel_speed", "base", positive=True),
            f.real(b, "wheel_max_torque", "base", positive=True),
            f.real(b, "wheel_friction", "base", 1.0, minimum=0.0),
            f.real(b, "wheel_spinning_friction", "base", 0.0, minimum=0.0),
            f.real(b, "wheel_rolling_friction", "base", 0.0, minimum=0.0),
            f.real(b, "wheel_axle_friction_scale", "base", 1.0, positive=True),
            f.real(b, "pivot_offset", "base", 0.0),
        )
    elif base_type == "holonomic":
        base = _holonomic_base(f, b)
    else:
        base = BaseSpec("fixed")

    a = f.section(data, "arm", ARM_KEYS)
    joints = f.names(a, "joints", "arm")
    vel = (
        f.vector(
            a.get("velocity_limits"),
            len(joints),
            a.line_of("velocity_limits"),
            "arm.velocity_limits",
        )
        or ()
    )
    if any(v <= 0 for v in vel):
        f.fail(a.line_of("velocity_limits"), "arm.velocity_limits must all be > 0")
    efforts: tuple[float | None, ...] = (None,) * len(joints)
    if "efforts" in a:
        efforts = f.vector(a["efforts"], len(joints), a.line_of("efforts"), "arm.efforts") or ()
    accel = tuple(ACCELERATION_PER_VELOCITY * v for v in vel)
    if "acceleration_limits" in a:
        accel = f.vector(a["acceleration_limits"], len(joints), a.line_of("acceleration_limits"),
                         "arm.acceleration_limits") or ()
        if any(v <= 0 for v in accel):
            f.fail(a.line_of("acceleration_limits"), "arm.acceleration_limits must all be > 0")
    arm_base = f.text(a, "base_link", "arm")
    gain = f.real(a, "position_gain", "arm", 0.3, positive=True)

    gripper = _gripper(f, data)

    raw_states = data.get("states")
    s = f.section(data, "states", set(raw_states) if isinstance(raw_states, dict) else set())
    states: dict[str, tuple[float, ...]] = {}
    for key in ("home", "tuck"):
        if key not in s:
            f.fail(s.line, f"states is missing '{key}' (arm positions in rad)")
    for key, value in s.items():
        q = f.vector(value, len(joints), s.line_of(key), f"states.{key}")
        if q is not None:
            states[key] = q

    fp = f.section(data, "footprint", FOOTPRINT_KEYS)
    if "radius" in fp:
        footprint = Footprint(radius=f.real(fp, "radius", "footprint", positive=True))
    else:
        footprint = Footprint(
            f.real(fp, "length", "footprint", positive=True),
            f.real(fp, "width", "footprint", positive=True),
            f.real(fp, "x_offset", "footprint", 0.0),
        )
    end_effector = f.text(data, "end_effector", "descriptor")
    grasp_link = f.text(data, "grasp_frame", "descriptor")
    spawn_height = f.real(data, "spawn_height", "descriptor", 0.0)
    approach_axis = str(data.get("approach_axis", "z"))
    if approach_axis not in APPROACH_AXES:
        f.fail(
            data.line_of("approach_axis"),
            f"approach_axis must be one of {', '.join(APPROACH_AXES)}, got {approach_axis!r}",
        )
    planning = _planning(f, data, path)
    sensors = read_sensors(f, data)
    if f.problems:
        raise InputError(f.problems)
    grasp_frame = grasp_link
    if approach_axis != "z":
        urdf = _with_approach_frame(urdf, name, grasp_link, APPROACH_AXES[approach_axis])
        grasp_frame = APPROACH_FRAME

    desc = RobotDescription(
        name,
        path,
        urdf,
        base,
        ArmSpec(arm_base, joints, vel, efforts, position_gain=gain, acceleration_limits=accel),
        gripper,
        end_effector,
        grasp_frame,
        states,
        footprint,
        spawn_height,
        approach_axis,
        grasp_link,
        planning,
        sensors,
    )
    return _check_against_urdf(desc, data, f)


def _planning(f: _Fields, data: LineDict, path: Path) -> PlanningSpec:
    """The ``planning`` section (absent: the defaults)."""
    p = f.section(data, "planning", PLANNING_KEYS, required=False)
    padding = f.number(p, "padding", "planning", DEFAULT_PADDING, within=(0.0, 0.2))
    allowed: dict[str, frozenset[frozenset[str]]] | None = None
    if "allowed_collisions" in p:
        raw = p["allowed_collisions"]
        m = f.mapping(raw, p.line_of("allowed_collisions"), "planning.allowed_collisions")
        allowed = {}
        if m is not None:
            f.unknown_keys(m, set(ALLOWED_REASONS), "planning.allowed_collisions")
            for reason in ALLOWED_REASONS:
                pairs: set[frozenset[str]] = set()
                for item in m.get(reason) or []:
                    if (not isinstance(item, list) or len(item) != 2
                            or not all(isinstance(v, str) and v for v in item)):
                        f.fail(m.line_of(reason), f"planning.allowed_collisions.{reason}: each "
                               f"entry must be a pair of link names, got {item!r}")
                        continue
                    pairs.add(frozenset(item))
                allowed[reason] = frozenset(pairs)
    srdf: Path | None = None
    if "srdf" in p:
        srdf = (path.parent / f.text(p, "srdf", "planning")).resolve()
        if not srdf.is_file():
            f.fail(p.line_of("srdf"), f"planning.srdf: no file {srdf}")
    return PlanningSpec(DEFAULT_PADDING if padding is None else padding, allowed, srdf)


def _with_approach_frame(
    urdf: Path | Recipe, name: str, grasp_link: str, rpy: tuple[float, float, float]
) -> Recipe:
    """``urdf`` (a file or a recipe) with :data:`APPROACH_FRAME` hung from ``grasp_link``."""
    frame = Frame(grasp_link, rpy=rpy)
    if isinstance(urdf, Recipe):
        return dataclasses.replace(urdf, frames={**urdf.frames, APPROACH_FRAME: frame})
    return Recipe(name, str(urdf), urdf.parent, frames={APPROACH_FRAME: frame})


def _gripper(f: _Fields, data: LineDict) -> GripperSpec:
    """The ``gripper`` section (absent: no gripper)."""
    g = f.section(data, "gripper", GRIPPER_KEYS, required=False)
    has_gripper = "gripper" in data
    joints = f.names(g, "joints", "gripper", required=has_gripper)
    kind = str(g.get("kind", "parallel"))
    if kind not in GRIPPER_KINDS:
        f.fail(g.line_of("kind"), f"gripper.kind must be one of {', '.join(GRIPPER_KINDS)}")
        kind = "parallel"
    ends: dict[str, tuple[float, ...]] = {}
    for key in ("open", "closed"):
        value = g.get(key)
        if isinstance(value, list) and kind != "parallel":
            ends[key] = f.vector(value, len(joints), g.line_of(key), f"gripper.{key}") or ()
        else:
            number = f.real(g, key, "gripper", None if has_gripper else 0.0)
            ends[key] = (number,) * len(joints)
    width = 0.0
    if kind != "parallel":
        width = f.real(g, "width", "gripper", None, positive=True)
    elif "width" in g:
        f.fail(g.line_of("width"), "gripper.width is for revolute and hand grippers; a "
               "parallel gripper's opening is the sum of its joints")
    opens, closeds = ends["open"], ends["closed"]
    if any(o == c for o, c in zip(opens, closeds, strict=False)):
        f.fail(g.line_of("open"), "gripper: a finger joint's open and closed positions are equal")
    return GripperSpec(
        joints,
        f.names(g, "finger_links", "gripper", required=has_gripper),
        opens[0] if opens else 0.0,
        closeds[0] if closeds else 0.0,
        f.real(g, "max_force", "gripper", None if has_gripper else 1.0, positive=True),
        f.real(g, "max_speed", "gripper", 0.1, positive=True),
        f.real(g, "pad_friction", "gripper", 1.5, minimum=0.0),
        kind,
        opens if kind != "parallel" else (),
        closeds if kind != "parallel" else (),
        width,
    )


HOLONOMIC_BOUNDS = {
    "max_speed": 5.0,
    "max_yaw_rate": 10.0,
    "max_accel": 20.0,
    "max_yaw_accel": 50.0,
    "max_force": 1e5,
    "max_torque": 1e5,
}
"""Upper bound of each number of a holonomic base (m/s, rad/s, m/s^2, rad/s^2, N, N m)."""


def _holonomic_base(f: _Fields, b: LineDict) -> BaseSpec:
    """The ``base`` section of a holonomic base (keys in ``robots/README.md``)."""
    joints = f.names(b, "joints", "base")
    if joints and len(joints) != 3:
        f.fail(b.line_of("joints"), "base.joints of a holonomic base: three joints, x, y and yaw")
    values: dict[str, float] = {}
    for key, top in HOLONOMIC_BOUNDS.items():
        default = 2.0 if key == "max_yaw_accel" else None
        value = f.number(b, key, "base", default, within=(1e-6, top))
        values[key] = 0.0 if value is None else value
    return BaseSpec(
        "holonomic",
        joints=joints,
        max_speed=values["max_speed"],
        max_yaw_rate=values["max_yaw_rate"],
        max_accel=values["max_accel"],
        max_yaw_accel=values["max_yaw_accel"],
        max_force=values["max_force"],
        max_torque=values["max_torque"],
    )


def _parse_urdf_source(f: _Fields, data: LineDict, path: Path) -> Path | Recipe:
    value = data.get("urdf")
    if isinstance(value, str):
        urdf = (path.parent / value).resolve()
        if not urdf.is_file():
            f.fail(data.line_of("urdf"), f"urdf: file '{value}' not found (at {urdf})")
        return urdf
    if isinstance(value, LineDict):
        try:
            return parse_recipe(value, path, data.get("name", path.stem))
        except InputError as exc:
            f.problems.extend(exc.problems)
            return path
    f.fail(data.line_of("urdf"), "urdf must be a file path or a composition recipe (mapping)")
    return path


@dataclass(frozen=True)
class _UrdfNames:
    """The link names of a URDF, and per joint name the attributes of its ``<limit>`` (None
    when it has none)."""

    links: frozenset[str | None]
    joints: Mapping[str | None, Mapping[str, str] | None]


_URDF_NAMES: Memo[_UrdfNames] = Memo(16)
"""The names read from URDFs in this process, keyed by the URDF's bytes."""


def _urdf_names(
    urdf: Path,
) -> tuple[frozenset[str | None], Mapping[str | None, Mapping[str, str] | None]]:
    """The link names of ``urdf`` and its joints' limits (read once per content and process:
    the file is read every time, parsed again only when its bytes are new)."""
    data = read_bounded(urdf, MAX_URDF_BYTES, "URDF file")
    key = bytes_key(data)
    names = _URDF_NAMES.get(key)
    if names is None:
        root = SafeET.fromstring(data)
        joints: dict[str | None, Mapping[str, str] | None] = {}
        for el in root.findall("joint"):
            limit = el.find("limit")
            joints[el.get("name")] = (
                MappingProxyType(dict(limit.attrib)) if limit is not None else None
            )
        names = _UrdfNames(
            frozenset(el.get("name") for el in root.findall("link")), MappingProxyType(joints)
        )
        _URDF_NAMES.put(key, names)
    return names.links, names.joints


def _check_against_urdf(desc: RobotDescription, data: LineDict, f: _Fields) -> RobotDescription:
    """Check every joint and link name of ``desc`` in its URDF; fill the arm's joint limits."""
    links, joints = _urdf_names(composed_urdf(desc))

    def need(names: tuple[str, ...], kind: Collection[str | None], section: str, key: str) -> None:
        sec = data.get(section) if section else data
        line = sec.line_of(key) if isinstance(sec, LineDict) else None
        for n in names:
            if n not in kind:
                what = "joint" if kind is joints else "link"
                f.fail(
                    line, f"{section + '.' if section else ''}{key}: no {what} '{n}' in the URDF"
                )

    need(desc.base.left_wheels + desc.base.right_wheels, joints, "base", "left_wheels")
    need(desc.base.joints, joints, "base", "joints")
    need(desc.arm.joints, joints, "arm", "joints")
    need((desc.arm.base_link,), links, "arm", "base_link")
    need(desc.gripper.joints, joints, "gripper", "joints")
    need(desc.gripper.finger_links, links, "gripper", "finger_links")
    need((desc.end_effector,), links, "", "end_effector")
    need((desc.grasp_link,), links, "", "grasp_frame")
    for pairs in (desc.planning.allowed or {}).values():
        need(tuple(sorted({n for pair in pairs for n in pair})), links,
             "planning", "allowed_collisions")
    for sensor in desc.sensors:
        if sensor.link not in links:
            f.fail(sensor.line, f"sensors: '{sensor.name}' is mounted on link '{sensor.link}', "
                   "which is not in the URDF")
    if f.problems:
        raise InputError(f.problems)
    lower, upper = [], []
    for n in desc.arm.joints:
        limit = joints[n]
        lo = float(limit.get("lower", -math.inf)) if limit is not None else -math.inf
        hi = float(limit.get("upper", math.inf)) if limit is not None else math.inf
        lower.append(lo)
        upper.append(hi)
    states = data["states"]
    for key, q in desc.states.items():
        bad = [desc.arm.joints[i] for i, v in enumerate(q) if not lower[i] <= v <= upper[i]]
        if bad:
            f.fail(states.line_of(key), f"states.{key}: outside the joint limits of {bad}")
    if f.problems:
        raise InputError(f.problems)
    arm = dataclasses.replace(desc.arm, lower=tuple(lower), upper=tuple(upper))
    return dataclasses.replace(desc, arm=arm)
