"""The world file's reader: YAML read into the checked records of :mod:`bt_manip.sim.world_spec`.

A world file describes, in metres, radians and kilograms (see ``worlds/README.md``):

``schema_version`` the format version the file is written for (optional, 1; a newer one is
               refused before anything else is read);
``walls``      static wall segments (``from``/``to``, ``thickness``, ``height``) with ``doors`` cut
               into them (``at`` = distance of the door centre from ``from``, ``width``);
``furniture``  static bodies: a primitive ``shape``, a list of ``parts``, or a ``urdf`` file;
``objects``    movable bodies, the same forms plus ``mass``, ``friction`` and ``randomize``;
``models``     movable bodies declared like ``objects`` but not spawned: a tree adds them
               (SpawnModel) and may remove them (DeleteModel);
``robots``     a robot ``description`` (``robots/<name>.yaml``), a start ``pose``, an
               ``arm_state``, ``randomize`` and a simulated ``battery`` (``percentage``,
               ``voltage``, ``drain`` per second);
``poses``      named planar poses ``[x, y, yaw]`` (or ``{x, y, qz, qw}``) for trees;
``groups``     entities moved together by one rigid motion (see :mod:`bt_manip.sim.groups`).

Every problem found is collected with its file and line; :func:`parse_world` raises one
:class:`~bt_manip.errors.InputError` with all of them.
"""

from __future__ import annotations

import copy
import difflib
import itertools
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import defusedxml.ElementTree as SafeET

from bt_manip.cache import Memo, bytes_key
from bt_manip.errors import InputError
from bt_manip.geometry import quat_from_euler, quat_from_yaw
from bt_manip.input_files import line_of_text, read_bounded
from bt_manip.sim.assets import resolve_uri
from bt_manip.sim.compose import MAX_URDF_BYTES
from bt_manip.sim.groups import parse_groups
from bt_manip.sim.mesh_check import mesh_problem
from bt_manip.sim.robot_description import find_descriptor, known_robots
from bt_manip.sim.urdf_bounds import check_urdf_size
from bt_manip.sim.world_spec import (
    COLOURS,
    DEFAULT_INITIAL_SIGMAS,
    WORLD_SCHEMA_VERSION,
    BatterySpec,
    BodySpec,
    DoorSpec,
    LocalizationSpec,
    Part,
    PhysicsSpec,
    Pose2D,
    Pose3D,
    Range2D,
    RobotSpec,
    WallSpec,
    WorldSpec,
)
from bt_manip.sim.yaml_lines import MAX_YAML_BYTES, FieldReader, LineDict, LineList, yaml_values

TOP_KEYS = {
    "schema_version",
    "name",
    "description",
    "physics",
    "walls",
    "furniture",
    "objects",
    "models",
    "robots",
    "poses",
    "groups",
    "route_graph",
    "localization",
}
LOCALIZATION_KEYS = {"min_particles", "max_particles", "initial_pose", "initial_sigmas",
                     "update_min_d", "update_min_a"}
PARTICLE_COUNTS = (1.0, 200_000.0)
"""Particle counts a ``localization:`` section accepts."""
INITIAL_SIGMA_BOUNDS = (0.0, 10.0)
"""Initial standard deviations (m or rad) a ``localization:`` section accepts."""
UPDATE_BOUNDS = (0.0, 10.0)
"""Travel (m) and turn (rad) thresholds a ``localization:`` section accepts."""
PHYSICS_KEYS = {"rate_hz", "gravity", "solver_iterations", "solver_tolerance", "ground_friction"}
WALL_KEYS = {"name", "from", "to", "thickness", "height", "colour", "color", "doors"}
DOOR_KEYS = {"at", "width"}
SHAPE_KEYS = {"shape", "size", "radius", "height"}
PART_KEYS = SHAPE_KEYS | {"xyz", "rpy", "colour", "color"}
BODY_KEYS = SHAPE_KEYS | {"name", "parts", "urdf", "scale", "pose", "colour", "color"}
OBJECT_KEYS = BODY_KEYS | {"mass", "friction", "randomize"}
ROBOT_KEYS = {"name", "description", "pose", "arm_state", "randomize", "battery"}
BATTERY_KEYS = {"percentage", "voltage", "drain"}
BATTERY_VOLTAGE = (0.0, 1000.0)
"""Battery voltages accepted (V)."""
RANDOM_KEYS = {"x", "y", "yaw"}


class _Reader(FieldReader):
    """Walks the YAML tree, converting values and collecting problems."""

    def colour(
        self, d: LineDict, where: str, default: tuple[float, float, float, float]
    ) -> tuple[float, float, float, float]:
        key = "colour" if "colour" in d else "color" if "color" in d else None
        if key is None:
            return default
        value = d[key]
        line = d.line_of(key)
        if isinstance(value, str):
            if value in COLOURS:
                return COLOURS[value]
            self.fail(
                line,
                f"{where}.{key}: unknown colour '{value}'; known: "
                f"{', '.join(sorted(COLOURS))}, or [r, g, b, a] in 0..1",
            )
            return default
        if isinstance(value, list) and len(value) in (3, 4):
            vec = self.vector(value, len(value), line, f"{where}.{key}")
            if vec is None:
                return default
            if any(not 0.0 <= c <= 1.0 for c in vec):
                self.fail(line, f"{where}.{key}: components must lie in 0..1")
                return default
            return (vec[0], vec[1], vec[2], vec[3] if len(vec) == 4 else 1.0)
        self.fail(line, f"{where}.{key} must be a colour name or [r, g, b, a]")
        return default

    def name(self, d: LineDict, where: str, fallback: str | None = None) -> str:
        value = d.get("name", fallback)
        if not isinstance(value, str) or not value.strip():
            self.fail(d.line_of("name"), f"{where} needs a non-empty 'name'")
            return fallback or "?"
        return value

    # -- poses --------------------------------------------------------------------------
    def pose2d(self, value: Any, line: int, where: str) -> Pose2D | None:
        if isinstance(value, list):
            vec = self.vector(value, 3, line, f"{where} ([x, y, yaw])")
            return Pose2D(*vec) if vec else None
        if isinstance(value, LineDict):
            allowed = {"x", "y", "yaw", "qz", "qw"}
            self.unknown_keys(value, allowed, where)
            x = self.number(value, "x", where)
            y = self.number(value, "y", where)
            if "yaw" in value and ("qz" in value or "qw" in value):
                self.fail(value.line, f"{where}: give either 'yaw' or 'qz'/'qw', not both")
                return None
            yaw: float | None
            if "qz" in value or "qw" in value:
                qz = self.number(value, "qz", where)
                qw = self.number(value, "qw", where)
                if qz is None or qw is None:
                    return None
                if math.hypot(qz, qw) < 1e-9:
                    self.fail(value.line, f"{where}: qz and qw cannot both be zero")
                    return None
                yaw = 2.0 * math.atan2(qz, qw)
            else:
                yaw = self.number(value, "yaw", where, default=0.0)
            if x is None or y is None or yaw is None:
                return None
            return Pose2D(x, y, yaw)
        self.fail(line, f"{where} must be [x, y, yaw] or {{x, y, yaw}} / {{x, y, qz, qw}}")
        return None

    def body_pose(self, value: Any, line: int, where: str) -> tuple[Pose3D, bool] | None:
        """``[x, y, yaw]`` (rests on the floor) or ``{xyz: [...], rpy|quat: [...]}``."""
        if isinstance(value, list) or (isinstance(value, LineDict) and "xyz" not in value):
            p2 = self.pose2d(value, line, where)
            if p2 is None:
                return None
            return Pose3D((p2.x, p2.y, 0.0), quat_from_yaw(p2.yaw)), True
        if isinstance(value, LineDict):
            self.unknown_keys(value, {"xyz", "rpy", "quat"}, where)
            xyz = self.vector(value["xyz"], 3, value.line_of("xyz"), f"{where}.xyz")
            if "rpy" in value and "quat" in value:
                self.fail(value.line, f"{where}: give either 'rpy' or 'quat', not both")
                return None
            quat: tuple[float, ...] | None = (0.0, 0.0, 0.0, 1.0)
            if "rpy" in value:
                rpy = self.vector(value["rpy"], 3, value.line_of("rpy"), f"{where}.rpy")
                quat = quat_from_euler(rpy) if rpy else None
            elif "quat" in value:
                quat = self.vector(value["quat"], 4, value.line_of("quat"), f"{where}.quat")
                if quat is not None:
                    norm = math.sqrt(sum(c * c for c in quat))
                    if norm < 1e-9:
                        self.fail(value.line_of("quat"), f"{where}.quat has zero length")
                        return None
                    quat = tuple(c / norm for c in quat)
            if xyz is None or quat is None:
                return None
            return Pose3D(xyz, quat), False  # type: ignore[arg-type]
        self.fail(line, f"{where} must be [x, y, yaw] or {{xyz: [x, y, z], rpy: [r, p, y]}}")
        return None

    def randomize(self, d: LineDict, where: str) -> Range2D:
        if "randomize" not in d:
            return Range2D()
        r = self.mapping(d["randomize"], d.line_of("randomize"), f"{where}.randomize")
        if r is None:
            return Range2D()
        self.unknown_keys(r, RANDOM_KEYS, f"{where}.randomize")
        out: dict[str, tuple[float, float]] = {}
        for key in RANDOM_KEYS & set(r):
            vec = self.vector(r[key], 2, r.line_of(key), f"{where}.randomize.{key} ([low, high])")
            if vec is not None:
                if vec[0] > vec[1]:
                    self.fail(
                        r.line_of(key), f"{where}.randomize.{key}: low {vec[0]} > high {vec[1]}"
                    )
                else:
                    out[key] = (vec[0], vec[1])
        return Range2D(**out)

    # -- shapes ---------------------------------------------------------------------------
    def shape(
        self, d: LineDict, where: str, colour: tuple[float, float, float, float], with_offset: bool
    ) -> Part | None:
        kind = d.get("shape")
        if kind not in ("box", "cylinder", "sphere"):
            self.fail(
                d.line_of("shape"), f"{where}.shape must be box, cylinder or sphere, got {kind!r}"
            )
            return None
        if kind == "box":
            size = self.vector(
                d.get("size"), 3, d.line_of("size"), f"{where}.size ([x, y, z] extents)"
            )
            if size is None:
                return None
            if any(s <= 0 for s in size):
                self.fail(d.line_of("size"), f"{where}.size must be positive, got {list(size)}")
                return None
        elif kind == "cylinder":
            r = self.number(d, "radius", where, positive=True)
            h = self.number(d, "height", where, positive=True)
            if r is None or h is None:
                return None
            size = (r, r, h)
        else:
            r = self.number(d, "radius", where, positive=True)
            if r is None:
                return None
            size = (r, r, 2 * r)
        xyz: tuple[float, ...] | None = (0.0, 0.0, 0.0)
        rpy: tuple[float, ...] | None = (0.0, 0.0, 0.0)
        if with_offset:
            if "xyz" in d:
                xyz = self.vector(d["xyz"], 3, d.line_of("xyz"), f"{where}.xyz")
            if "rpy" in d:
                rpy = self.vector(d["rpy"], 3, d.line_of("rpy"), f"{where}.rpy")
        if xyz is None or rpy is None:
            return None
        return Part(kind, size, xyz, rpy, colour)  # type: ignore[arg-type]


def _parse_walls(rd: _Reader, walls: LineList) -> list[WallSpec]:
    out: list[WallSpec] = []
    for i, where, d in rd.entries(walls, "walls", WALL_KEYS):
        start = rd.vector(d.get("from"), 2, d.line_of("from"), f"{where}.from ([x, y])")
        end = rd.vector(d.get("to"), 2, d.line_of("to"), f"{where}.to ([x, y])")
        thickness = rd.number(d, "thickness", where, default=0.12, positive=True)
        height = rd.number(d, "height", where, default=1.0, positive=True)
        colour = rd.colour(d, where, COLOURS["beige"])
        name = rd.name(d, where, fallback=f"wall_{i}")
        if start is None or end is None or thickness is None or height is None:
            continue
        length = math.dist(start, end)
        if length < 1e-6:
            rd.fail(d.line, f"{where}: 'from' and 'to' are the same point")
            continue
        doors: list[DoorSpec] = []
        door_list = rd.seq(d.get("doors"), d.line_of("doors"), f"{where}.doors")
        for _, dw, dd in rd.entries(door_list, f"{where}.doors", DOOR_KEYS):
            at = rd.number(dd, "at", dw)
            width = rd.number(dd, "width", dw, positive=True)
            if at is None or width is None:
                continue
            if at - width / 2 < 0 or at + width / 2 > length:
                rd.fail(
                    dd.line,
                    f"{dw}: door from {at - width / 2:.3f} to {at + width / 2:.3f} m "
                    f"does not fit in the wall of length {length:.3f} m",
                )
                continue
            doors.append(DoorSpec(at, width, dd.line))
        doors.sort(key=lambda door: door.at)
        for a, b in itertools.pairwise(doors):
            if a.at + a.width / 2 > b.at - b.width / 2:
                rd.fail(b.line, f"{where}: doors at {a.at} m and {b.at} m overlap")
        out.append(WallSpec(name, start, end, thickness, height, colour, doors, d.line))  # type: ignore[arg-type]
    return out


def _parse_body(rd: _Reader, d: LineDict, where: str, movable: bool, base: Path) -> BodySpec | None:
    rd.unknown_keys(d, OBJECT_KEYS if movable else BODY_KEYS, where)
    name = rd.name(d, where)
    colour = rd.colour(d, where, COLOURS["wood"] if not movable else COLOURS["orange"])
    forms = [k for k in ("shape", "parts", "urdf") if k in d]
    if len(forms) != 1:
        rd.fail(
            d.line,
            f"{where} ('{name}') needs exactly one of 'shape', 'parts' or 'urdf', "
            f"got {forms or 'none'}",
        )
        return None
    parts: list[Part] = []
    urdf: Path | None = None
    if "shape" in d:
        part = rd.shape(d, where, colour, with_offset=False)
        if part is None:
            return None
        parts = [part]
    elif "parts" in d:
        plist = rd.seq(d["parts"], d.line_of("parts"), f"{where}.parts")
        if not plist:
            rd.fail(d.line_of("parts"), f"{where}.parts must list at least one part")
            return None
        for _, pw, pd in rd.entries(plist, f"{where}.parts", PART_KEYS):
            part = rd.shape(pd, pw, rd.colour(pd, pw, colour), with_offset=True)
            if part is not None:
                parts.append(part)
        if len(parts) != len(plist):
            return None
    else:
        raw = d["urdf"]
        if not isinstance(raw, str):
            rd.fail(d.line_of("urdf"), f"{where}.urdf must be a path")
            return None
        urdf = resolve_uri(raw, base)
        if not urdf.is_file():
            rd.fail(d.line_of("urdf"), f"{where}.urdf: file not found: {raw} (looked at {urdf})")
            return None
        for problem in _check_urdf_meshes(urdf):
            rd.fail(d.line_of("urdf"), f"{where}.urdf: {problem}")
    scale = rd.number(d, "scale", where, default=1.0, positive=True) or 1.0
    mass = 0.0
    friction = 0.8
    if movable:
        m = rd.number(d, "mass", where, positive=True)
        if m is None:
            return None
        mass = m
        friction = rd.number(d, "friction", where, default=0.8, non_negative=True) or 0.0
    if "pose" not in d:
        rd.fail(d.line, f"{where} ('{name}') is missing 'pose'")
        return None
    got = rd.body_pose(d["pose"], d.line_of("pose"), f"{where}.pose")
    if got is None:
        return None
    pose, planar = got
    randomize = rd.randomize(d, where) if movable else Range2D()
    return BodySpec(
        name, movable, parts, urdf, pose, planar, mass, friction, colour, randomize, d.line, scale
    )


def _check_urdf_meshes(urdf: Path) -> list[str]:
    """Every mesh a URDF names must exist (relative to the file, or a known package URI) and
    be a mesh PyBullet reads; each problem names the URDF (and line) and the mesh."""
    try:
        data = read_bounded(urdf, MAX_URDF_BYTES, "URDF file")
    except InputError as exc:
        return [exc.problems[0].message + f" ({urdf.name})"]
    try:
        root = SafeET.fromstring(data)
    except Exception as exc:
        return [f"cannot parse {urdf.name}: {exc}"]
    try:
        check_urdf_size(urdf, root, data)
    except InputError as exc:
        first = exc.problems[0]
        where = f"{urdf.name}:{first.line}" if first.line else urdf.name
        return [f"{first.message} ({where})"]
    names = dict.fromkeys(mesh.get("filename", "") for mesh in root.iter("mesh"))
    out = []
    for fn in names:
        problem = mesh_problem(resolve_uri(fn, urdf.parent), fn)
        if problem is not None:
            line = line_of_text(data, fn)
            where = f"{urdf.name}:{line}" if line else urdf.name
            out.append(f"{problem} (named in {where})")
    return out


def _parse_robots(rd: _Reader, robots: LineList, base: Path) -> list[RobotSpec]:
    out: list[RobotSpec] = []
    for _, where, d in rd.entries(robots, "robots", ROBOT_KEYS):
        name = rd.name(d, where)
        desc = d.get("description")
        if not isinstance(desc, str):
            rd.fail(
                d.line_of("description"),
                f"{where} ('{name}') needs 'description': a robot "
                f"name such as {', '.join(known_robots(base)) or 'husky_ur3'}",
            )
            continue
        desc_path = find_descriptor(desc, base)
        if desc_path is None:
            known = known_robots(base)
            close = difflib.get_close_matches(desc, known, n=1)
            hint = (
                f"did you mean '{close[0]}'?" if close else f"known: {', '.join(known) or 'none'}"
            )
            rd.fail(d.line_of("description"), f"{where}: unknown robot '{desc}'; {hint}")
            continue
        pose = rd.pose2d(d.get("pose", [0, 0, 0]), d.line_of("pose"), f"{where}.pose")
        arm_state = d.get("arm_state")
        if arm_state is not None and not isinstance(arm_state, str):
            rd.fail(d.line_of("arm_state"), f"{where}.arm_state must be a state name")
            arm_state = None
        if pose is None:
            continue
        out.append(
            RobotSpec(name, desc, desc_path, pose, arm_state, rd.randomize(d, where), d.line,
                      _parse_battery(rd, d, where))
        )
    return out


def _parse_battery(rd: _Reader, d: LineDict, where: str) -> BatterySpec:
    """A robot's ``battery`` mapping (absent: full, 12 V, no drain)."""
    if "battery" not in d:
        return BatterySpec()
    b = rd.mapping(d["battery"], d.line_of("battery"), f"{where}.battery")
    if b is None:
        return BatterySpec()
    here = f"{where}.battery"
    rd.unknown_keys(b, BATTERY_KEYS, here)
    default = BatterySpec()
    percentage = rd.number(b, "percentage", here, default.percentage, within=(0.0, 1.0))
    voltage = rd.number(b, "voltage", here, default.voltage, within=BATTERY_VOLTAGE)
    drain = rd.number(b, "drain", here, default.drain, within=(0.0, 1.0))
    return BatterySpec(
        default.percentage if percentage is None else percentage,
        default.voltage if voltage is None else voltage,
        default.drain if drain is None else drain,
    )


PHYSICS_RATES = (10.0, 10_000.0)
"""Physics rates accepted (Hz): every tick steps rate / tick rate times."""
SOLVER_ITERATIONS = (1.0, 1000.0)
SOLVER_TOLERANCE = (0.0, 1.0)
"""Solver iterations per physics step accepted."""


@dataclass(frozen=True)
class _KnownWorld:
    """A world file's spec as parsed, and where its robots' descriptors were found."""

    spec: WorldSpec
    descriptors: tuple[tuple[str, Path], ...]


_WORLD_MEMO: Memo[_KnownWorld] = Memo(16)


def parse_world(path: str | Path) -> WorldSpec:
    """Read and check a world file; raise InputError listing every problem found.

    The file is read every time. A world file read before in this process, with the same
    bytes, named by the same path, whose robots' descriptors are found at the same files and
    that names no URDF (whose files and meshes would need checking again), is not parsed
    again: the caller gets a copy of the spec parsed then, which is what parsing would give.
    """
    spec, kept = _checked_world(path)
    return copy.deepcopy(spec) if kept else spec


def check_world(path: str | Path) -> None:
    """Check a world file as :func:`parse_world` does (the same problems raised), for a caller
    that needs no spec: one known already is not copied."""
    _checked_world(path)


def _checked_world(path: str | Path) -> tuple[WorldSpec, bool]:
    """The world file's spec, and whether it is the one kept from an earlier read (which the
    caller must not change)."""
    path = Path(path)
    data = read_bounded(path, MAX_YAML_BYTES, "YAML file")
    base = path.resolve().parent
    key = (str(path), str(base), bytes_key(data))
    known = _WORLD_MEMO.get(key)
    if known is not None and all(
        find_descriptor(name, base) == found for name, found in known.descriptors
    ):
        return known.spec, True
    spec = _parse_world(path, data)
    if all(b.urdf is None for b in spec.furniture + spec.objects + spec.models):
        found = tuple((r.description, r.description_path) for r in spec.robots)
        _WORLD_MEMO.put(key, _KnownWorld(copy.deepcopy(spec), found))
    return spec, False


def _parse_world(path: Path, raw: bytes) -> WorldSpec:
    """The checked spec of the world file ``path`` whose bytes are ``raw``."""
    data = yaml_values(path, raw)
    rd = _Reader(path)
    if not isinstance(data, LineDict):
        raise InputError.single(
            str(path),
            1,
            "a world file must be a YAML mapping (name, walls, furniture, objects, robots, poses)",
        )
    _check_schema_version(path, data)
    rd.unknown_keys(data, TOP_KEYS, "the world")
    base = path.resolve().parent
    physics = PhysicsSpec()
    if "physics" in data:
        ph = rd.mapping(data["physics"], data.line_of("physics"), "physics")
        if ph is not None:
            rd.unknown_keys(ph, PHYSICS_KEYS, "physics")
            physics.rate_hz = (
                rd.number(ph, "rate_hz", "physics", 240.0, within=PHYSICS_RATES) or 240.0
            )
            if "gravity" in ph:
                g = rd.vector(ph["gravity"], 3, ph.line_of("gravity"), "physics.gravity")
                physics.gravity = g or physics.gravity  # type: ignore[assignment]
            physics.solver_iterations = int(
                rd.number(ph, "solver_iterations", "physics", 50, within=SOLVER_ITERATIONS) or 50
            )
            if "solver_tolerance" in ph:
                physics.solver_tolerance = rd.number(
                    ph, "solver_tolerance", "physics", None, within=SOLVER_TOLERANCE
                )
            physics.ground_friction = (
                rd.number(ph, "ground_friction", "physics", 1.0, non_negative=True) or 0.0
            )
    spec = WorldSpec(path=path, name=str(data.get("name", path.stem)), physics=physics)
    walls = rd.seq(data.get("walls"), data.line_of("walls"), "walls")
    spec.walls = _parse_walls(rd, walls) if walls else []
    lists = {"furniture": spec.furniture, "objects": spec.objects, "models": spec.models}
    for key, target in lists.items():
        items = rd.seq(data.get(key), data.line_of(key), key)
        for _, where, d in rd.entries(items, key):
            body = _parse_body(rd, d, where, key != "furniture", base)
            if body is not None:
                target.append(body)
    robots = rd.seq(data.get("robots"), data.line_of("robots"), "robots")
    spec.robots = _parse_robots(rd, robots, base) if robots else []
    if "poses" in data:
        poses = rd.mapping(data["poses"], data.line_of("poses"), "poses")
        for name, raw in (poses or {}).items():
            p = rd.pose2d(raw, poses.line_of(name), f"poses.{name}")  # type: ignore[union-attr]
            if p is not None:
                spec.poses[name] = p
                spec.pose_lines[name] = poses.line_of(name)  # type: ignore[union-attr]
    spec.groups = parse_groups(rd, data, spec)
    if "route_graph" in data:
        name = rd.text(data, "route_graph", "the world")  # "" after reporting a non-text value
        if name:
            graph = base / name
            if not graph.is_file():
                rd.fail(data.line_of("route_graph"), f"route_graph: no file {graph}")
            spec.route_graph = graph
    if "localization" in data:
        spec.localization = _parse_localization(rd, data)
    _check_unique_names(rd, spec)
    if rd.problems:
        raise InputError(rd.problems)
    return spec


def _parse_localization(rd: _Reader, data: LineDict) -> LocalizationSpec | None:
    """The world's ``localization:`` section (every key optional; an empty one means the
    defaults)."""
    line = data.line_of("localization")
    raw = data["localization"]
    if raw is None:
        return LocalizationSpec(line=line)
    d = rd.mapping(raw, line, "localization")
    if d is None:
        return None
    here = "localization"
    rd.unknown_keys(d, LOCALIZATION_KEYS, here)
    counts: dict[str, int | None] = {}
    for key in ("min_particles", "max_particles"):
        v = rd.number(d, key, here, None, within=PARTICLE_COUNTS) if key in d else None
        if v is not None and v != int(v):
            rd.fail(d.line_of(key), f"{here}.{key} must be a whole number, not {v:g}")
            v = None
        counts[key] = int(v) if v is not None else None
    lo, hi = counts["min_particles"], counts["max_particles"]
    if lo is not None and hi is not None and lo > hi:
        rd.fail(d.line_of("min_particles"),
                f"{here}.min_particles ({lo}) must not exceed max_particles ({hi})")
    pose = None
    if "initial_pose" in d:
        pose = rd.pose2d(d["initial_pose"], d.line_of("initial_pose"), f"{here}.initial_pose")
    sigmas = DEFAULT_INITIAL_SIGMAS
    if "initial_sigmas" in d:
        where = f"{here}.initial_sigmas ([sigma_x, sigma_y, sigma_yaw])"
        vec = rd.vector(d["initial_sigmas"], 3, d.line_of("initial_sigmas"), where)
        if vec:
            if all(INITIAL_SIGMA_BOUNDS[0] <= v <= INITIAL_SIGMA_BOUNDS[1] for v in vec):
                sigmas = (float(vec[0]), float(vec[1]), float(vec[2]))
            else:
                rd.fail(d.line_of("initial_sigmas"),
                        f"{here}.initial_sigmas must each be within 0..10, not {list(vec)}")
    update_d, update_a = (rd.number(d, k, here, None, within=UPDATE_BOUNDS) if k in d else None
                          for k in ("update_min_d", "update_min_a"))
    return LocalizationSpec(lo, hi, pose, sigmas, update_d, update_a, line)


def _check_schema_version(path: Path, data: LineDict) -> None:
    """Refuse a world written for another format version, before any other check (a newer
    format's keys would otherwise be reported one by one as unknown)."""
    if "schema_version" not in data:
        return
    version = data["schema_version"]
    line = data.line_of("schema_version")
    if isinstance(version, bool) or not isinstance(version, int) or version < 1:
        raise InputError.single(
            str(path), line,
            f"schema_version must be a whole number >= 1, got {version!r} (this bt-manip reads "
            f"version {WORLD_SCHEMA_VERSION})",
        )
    if version > WORLD_SCHEMA_VERSION:
        raise InputError.single(
            str(path), line,
            f"schema_version {version} is newer than the world format this bt-manip reads "
            f"(version {WORLD_SCHEMA_VERSION}); upgrade bt-manip to load this world",
        )


def _check_unique_names(rd: _Reader, spec: WorldSpec) -> None:
    seen: dict[str, int] = {}
    entries: list[tuple[str, int]] = [(w.name, w.line) for w in spec.walls]
    entries += [(b.name, b.line) for b in spec.furniture + spec.objects + spec.models]
    entries += [(r.name, r.line) for r in spec.robots]
    for name, line in entries:
        if name in seen:
            rd.fail(
                line,
                f"name '{name}' is used twice (first at line {seen[name]}); names must be unique",
            )
        else:
            seen[name] = line
