"""``bt-manip robot init``: a robot descriptor written from a URDF.

Given a URDF and a few names (the arm's base link and tip, the gripper's finger joints, the kind
of mobile base), :func:`init_descriptor` reads the URDF and writes ``robots/<name>.yaml`` in the
format of ``robots/README.md``:

- the arm chain from the base link down to the tip: its movable joints in order, their speed
  and effort limits (lower / upper are read from the URDF at load time);
- the gripper: each finger joint must be prismatic or revolute; the open and closed positions
  are its upper and lower limits, the force and speed its effort and velocity limits;
- named arm states ``zero`` (every joint at 0, clipped into its limits), ``ready`` (the middle
  of each joint's range, 0 for joints without limits), ``home`` (= ``ready``) and ``tuck``
  (= ``zero``), all within the limits;
- the footprint from the collision shapes: for a fixed arm the circle around the links that no
  arm joint moves, for a mobile base the rectangle around the base links;
- for ``skid``/``diff`` bases the wheels (continuous joints off the arm, left / right by the
  side of the root frame they sit on), their radius, track width and the spawn height that puts
  the wheels on the floor;
- for a ``holonomic`` base the three virtual joints above the base link (prismatic x, prismatic
  y, then a continuous or revolute yaw joint, see :func:`holonomic_joints`), the speed limits
  from their URDF velocities, the motor force and torque from their URDF efforts (else from the
  robot's weight), and a spawn height that keeps the base just clear of the floor.

The file refers to the URDF by a URI (``package://example-robot-data/...``,
``pybullet_data://...``) or by a path relative to the descriptor, never an absolute path. The
result is then loaded the way a world loads robots (:func:`load_description`, plus the arm's
kinematic model); the descriptor is only kept when that works. Every problem is an
:class:`~bt_manip.errors.InputError` naming file and line.
"""

from __future__ import annotations

import contextlib
import dataclasses
import math
import os
import re
import tempfile
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import defusedxml.ElementTree as SafeET
import numpy as np

from bt_manip.errors import InputError, Problem
from bt_manip.geometry import rpy_matrix
from bt_manip.input_files import read_bounded
from bt_manip.sim.assets import example_robot_data_share, pybullet_data_dir
from bt_manip.sim.compose import MAX_URDF_BYTES, composed_urdf
from bt_manip.sim.gripper_survey import (
    Body,
    GripperSurvey,
    SurveyError,
    approach_axis,
    enclosing_leaf_links,
    expand_joint_patterns,
    survey_gripper,
)
from bt_manip.sim.robot_description import APPROACH_AXES, RobotDescription, load_description
from bt_manip.sim.urdf_bounds import check_urdf_size

__all__ = ["MOBILE_KINDS", "InitOptions", "holonomic_joints", "init_descriptor", "urdf_uri"]

MOBILE_KINDS = ("skid", "diff", "holonomic")
MOVABLE = ("revolute", "continuous", "prismatic")
DEFAULT_VELOCITY = 1.0
"""rad/s (or m/s) for a joint whose URDF gives no velocity limit."""
DEFAULT_WHEEL_SPEED = 6.0
DEFAULT_WHEEL_TORQUE = 50.0
MAX_NAME = 64
CASTER_GAP = 0.01
"""m: a link whose lowest point is this close to the wheels' contact with the floor rests on it."""
HOLONOMIC_SPEED = 0.5
"""m/s of a holonomic base whose x / y joints give no velocity limit."""
HOLONOMIC_YAW_RATE = 1.0
"""rad/s of a holonomic base whose yaw joint gives no velocity limit."""
HOLONOMIC_ACCEL = 0.5
"""m/s^2: the acceleration limit written for a holonomic base's path follower."""
PUSH_FRICTION = 0.5
"""Without URDF efforts, a holonomic base pushes with this fraction of its weight (what
wheels with this friction coefficient could push with)."""
FLOOR_GAP = 0.03
"""m between the floor and the lowest collision shape of a holonomic base at spawn. The
virtual joints carry the base; closer than PyBullet's contact threshold (a few cm), the floor
would count as touching it and its friction would tug at the base and the arm on it."""
HOLONOMIC_AXES = (
    ("x", ("prismatic",), (1.0, 0.0, 0.0)),
    ("y", ("prismatic",), (0.0, 1.0, 0.0)),
    ("yaw", ("continuous", "revolute"), (0.0, 0.0, 1.0)),
)
"""What the three virtual joints of a holonomic base must be, root first."""


@dataclass(frozen=True)
class InitOptions:
    """What ``robot init`` is told: the URDF, the names in it and where to write."""

    urdf: Path
    base_link: str
    arm_tip: str
    out: Path
    gripper: tuple[str, ...] = ()
    mobile: str | None = None
    name: str = ""
    grasp_frame: str = ""
    approach_axis: str = ""
    """``x``, ``-y``, ...: the grasp frame's axis the gripper approaches along; "" = found."""
    lidar: str = ""
    """A link carrying a planar laser (its origin, scanning in its x-y plane); "" = none."""


@dataclass(frozen=True)
class _Joint:
    name: str
    type: str
    parent: str
    child: str
    line: int | None
    lower: float
    upper: float
    velocity: float | None
    effort: float | None
    axis: tuple[float, ...] = (1.0, 0.0, 0.0)
    rpy: tuple[float, ...] = (0.0, 0.0, 0.0)


class _Urdf:
    """The links and joints of a URDF with the line each is declared on."""

    def __init__(self, path: Path) -> None:
        self.path = path
        data = read_bounded(path, MAX_URDF_BYTES, "URDF file")
        try:
            root = SafeET.fromstring(data)
        except ET.ParseError as exc:
            line = exc.position[0] if exc.position else None
            raise InputError.single(str(path), line, f"the URDF does not parse: {exc}") from None
        except Exception as exc:  # defusedxml refuses entities and DTDs with its own errors
            raise InputError.single(str(path), None, f"the URDF does not parse: {exc}") from None
        if root.tag != "robot":
            raise InputError.single(str(path), 1, f"root element is <{root.tag}>, not <robot>")
        check_urdf_size(path, root, data)
        self.robot_name = root.get("name", "") or path.stem
        text = data.decode("utf-8", errors="replace")
        lines = _declared_lines(text)
        self.links: dict[str, int | None] = {}
        self.round_shapes: dict[str, tuple[float, tuple[float, float, float] | None]] = {}
        """Links whose only collision shape is a cylinder or a sphere: its radius and, for a
        cylinder, its axis in the link frame."""
        self.shaped: set[str] = set()
        """Links with at least one collision shape."""
        for el in root.findall("link"):
            name = el.get("name", "")
            self.links[name] = lines.get(("link", name))
            if el.find("collision") is not None:
                self.shaped.add(name)
            round_shape = _round_shape(el)
            if round_shape is not None:
                self.round_shapes[name] = round_shape
        self.joints: dict[str, _Joint] = {}
        self.mimics: dict[str, tuple[str, float, float]] = {}
        """Follower joint -> (leader, multiplier, offset)."""
        for el in root.findall("joint"):
            name = el.get("name", "")
            jline = lines.get(("joint", name))
            mimic = el.find("mimic")
            if mimic is not None and mimic.get("joint"):
                with contextlib.suppress(ValueError):
                    self.mimics[name] = (mimic.get("joint", ""),
                                         float(mimic.get("multiplier", "1")),
                                         float(mimic.get("offset", "0")))

            def num(key: str, default: float | None, el: ET.Element = el,
                    where: tuple[str, int | None] = (name, jline)) -> float | None:
                return _limit_value(path, el, key, default, *where)

            jtype = el.get("type", "")
            bounded = jtype in ("revolute", "prismatic")
            self.joints[name] = _Joint(
                name,
                jtype,
                _end(el, "parent"),
                _end(el, "child"),
                jline,
                (num("lower", 0.0) or 0.0) if bounded else -math.inf,
                (num("upper", 0.0) or 0.0) if bounded else math.inf,
                num("velocity", None),
                num("effort", None),
                _triple(el, "axis", "xyz", (1.0, 0.0, 0.0)),
                _triple(el, "origin", "rpy", (0.0, 0.0, 0.0)),
            )
        self.parent_joint = {j.child: j for j in self.joints.values()}

    def problem(self, line: int | None, message: str) -> Problem:
        return Problem(str(self.path), line, message)

    def chain(self, base: str, tip: str) -> list[_Joint] | None:
        """Joints from ``base`` down to ``tip`` (all kinds), or None if tip is not below base."""
        out: list[_Joint] = []
        link = tip
        for _ in range(len(self.joints) + 1):
            if link == base:
                return out[::-1]
            joint = self.parent_joint.get(link)
            if joint is None:
                return None
            out.append(joint)
            link = joint.parent
        return None

    def below(self, link: str) -> set[str]:
        """``link`` and every link below it."""
        children: dict[str, list[str]] = {}
        for j in self.joints.values():
            children.setdefault(j.parent, []).append(j.child)
        seen = {link}
        todo = [link]
        while todo:
            for c in children.get(todo.pop(), []):
                if c not in seen:
                    seen.add(c)
                    todo.append(c)
        return seen

    def leaves(self) -> list[str]:
        """Links no joint hangs from."""
        parents = {j.parent for j in self.joints.values()}
        return [name for name in self.links if name not in parents]

    def root_link(self) -> str:
        roots = [name for name in self.links if name not in self.parent_joint]
        return roots[0] if roots else ""


def _limit_value(
    path: Path, joint: ET.Element, key: str, default: float | None, name: str, line: int | None
) -> float | None:
    """Attribute ``key`` of the joint's ``<limit>`` as a finite number, ``default`` if absent."""
    limit = joint.find("limit")
    if limit is None or limit.get(key) is None:
        return default
    raw = limit.get(key, "")
    try:
        value = float(raw)
    except ValueError:
        value = math.nan
    if not math.isfinite(value):
        raise InputError.single(
            str(path), line, f"joint '{name}': limit {key}={raw!r} is not a finite number"
        )
    return value


def _round_shape(link: ET.Element) -> tuple[float, tuple[float, float, float] | None] | None:
    """The radius (and a cylinder's axis) of a link's single cylinder or sphere collision."""
    collisions = link.findall("collision")
    if len(collisions) != 1:
        return None
    geometry = collisions[0].find("geometry")
    shapes = list(geometry) if geometry is not None else []
    if len(shapes) != 1 or shapes[0].tag not in ("cylinder", "sphere"):
        return None
    try:
        radius = float(shapes[0].get("radius", ""))
    except ValueError:
        return None
    if not math.isfinite(radius) or radius <= 0.0:
        return None
    if shapes[0].tag == "sphere":
        return radius, None
    roll, pitch, yaw = _triple(collisions[0], "origin", "rpy", (0.0, 0.0, 0.0))
    axis = rpy_matrix(roll, pitch, yaw)[:, 2]
    return radius, (float(axis[0]), float(axis[1]), float(axis[2]))


def _rolling_radius(urdf: _Urdf, joint: _Joint) -> float | None:
    """A wheel's radius from its URDF shape: a sphere, or a cylinder turning about its own
    axis; None otherwise (the caller measures the shape instead)."""
    shape = urdf.round_shapes.get(joint.child)
    if shape is None:
        return None
    radius, axis = shape
    if axis is None:
        return radius
    turn = np.asarray(joint.axis, dtype=float)
    norm = float(np.linalg.norm(turn))
    if norm == 0.0 or abs(float(np.dot(axis, turn))) < 0.99 * norm:
        return None
    return radius


def _triple(
    joint: ET.Element, tag: str, key: str, default: tuple[float, ...]
) -> tuple[float, ...]:
    """Attribute ``key`` of the joint's ``<tag>`` as three numbers (``default`` if absent or
    not three finite numbers: the loader reports such a file)."""
    found = joint.find(tag)
    try:
        values = tuple(float(v) for v in found.get(key, "").split()) if found is not None else ()
    except ValueError:
        values = ()
    if len(values) != 3 or not all(math.isfinite(v) for v in values):
        return default
    return values


_DECLARED = re.compile(r"""<(link|joint) name=(["'])(.*?)\2""")


def _declared_lines(text: str) -> dict[tuple[str, str], int]:
    """The line of each ``<link name="...">`` and ``<joint name="...">`` of a URDF's text,
    by (tag, name): the first declaration of a name (one pass over the text)."""
    out: dict[tuple[str, str], int] = {}
    line, counted = 1, 0
    for match in _DECLARED.finditer(text):
        line += text.count("\n", counted, match.start())
        counted = match.start()
        out.setdefault((match.group(1), match.group(3)), line)
    return out


def _end(el: ET.Element, which: str) -> str:
    found = el.find(which)
    return found.get("link", "") if found is not None else ""


def urdf_uri(urdf: Path, descriptor_folder: Path) -> str:
    """How a descriptor in ``descriptor_folder`` names ``urdf``: a URI, else a relative path."""
    urdf = urdf.resolve()
    try:
        share = example_robot_data_share()
        return "package://" + urdf.relative_to(share).as_posix()
    except (ValueError, FileNotFoundError, ImportError):
        pass
    try:
        return "pybullet_data://" + urdf.relative_to(pybullet_data_dir().resolve()).as_posix()
    except (ValueError, ImportError):
        pass
    return Path(os.path.relpath(urdf, descriptor_folder.resolve())).as_posix()


def _fmt(value: float) -> str:
    text = f"{value:.4f}".rstrip("0")
    return text + "0" if text.endswith(".") else text


def _vector(values: list[float]) -> str:
    return "[" + ", ".join(_fmt(v) for v in values) + "]"


def _state(values: list[float], lower: list[float], upper: list[float]) -> str:
    """Like :func:`_vector`, full precision where rounding would leave the joint limits."""
    out = []
    for v, lo, hi in zip(values, lower, upper, strict=True):
        short = _fmt(v)
        out.append(short if lo <= float(short) <= hi else repr(float(v)))
    return "[" + ", ".join(out) + "]"


def _check_names(urdf: _Urdf, opts: InitOptions) -> list[Problem]:
    problems: list[Problem] = []
    root_line = 1
    for key, link in (("--base-link", opts.base_link), ("--arm-tip", opts.arm_tip)):
        if link not in urdf.links:
            problems.append(
                urdf.problem(root_line, f"{key}: no link '{link}' in the URDF; links: "
                             f"{', '.join(list(urdf.links)[:40])}")
            )
    if opts.grasp_frame and opts.grasp_frame not in urdf.links:
        problems.append(
            urdf.problem(root_line, f"--grasp-frame: no link '{opts.grasp_frame}' in the URDF")
        )
    for name in opts.gripper:
        joint = urdf.joints.get(name)
        if joint is None:
            problems.append(urdf.problem(root_line, f"--gripper: no joint '{name}' in the URDF"))
        elif joint.type not in ("prismatic", "revolute"):
            problems.append(
                urdf.problem(
                    joint.line,
                    f"--gripper: joint '{name}' is {joint.type or 'untyped'}; a finger joint "
                    "must be prismatic or revolute",
                )
            )
    if opts.lidar and opts.lidar not in urdf.links:
        problems.append(
            urdf.problem(root_line, f"--lidar: no link '{opts.lidar}' in the URDF")
        )
    if opts.approach_axis and opts.approach_axis not in APPROACH_AXES:
        problems.append(urdf.problem(
            None, f"--approach-axis must be one of {', '.join(APPROACH_AXES)}"
        ))
    if opts.mobile is not None and opts.mobile not in MOBILE_KINDS:
        problems.append(
            urdf.problem(None, f"--mobile must be one of {', '.join(MOBILE_KINDS)}")
        )
    return problems


def holonomic_joints(urdf: _Urdf, base_link: str) -> list[_Joint]:
    """The virtual joints of a holonomic base above ``base_link``, root first: prismatic x,
    prismatic y, then a continuous or revolute yaw joint (fixed joints may sit between them).

    Their axes must be the x, y and z axes of their joint frames and their origins unrotated,
    so that x and y move along the root frame's axes. Raises
    :class:`~bt_manip.errors.InputError` with the line of the joint (or of the base link) that
    does not fit.
    """
    above: list[_Joint] = []
    link = base_link
    for _ in range(len(urdf.joints) + 1):
        joint = urdf.parent_joint.get(link)
        if joint is None:
            break
        if joint.type != "fixed":
            above.append(joint)
        link = joint.parent
    above.reverse()
    want = "a prismatic x joint, a prismatic y joint and a continuous (or revolute) yaw joint"
    if len(above) != 3:
        names = ", ".join(f"'{j.name}' ({j.type})" for j in above) or "none"
        raise InputError.single(
            str(urdf.path), urdf.links.get(base_link),
            f"--mobile holonomic: {len(above)} movable joint(s) above --base-link "
            f"'{base_link}' ({names}); a holonomic base hangs from the root link by {want}, "
            "in that order",
        )
    for joint, (label, types, axis) in zip(above, HOLONOMIC_AXES, strict=True):
        kind = " or ".join(types)
        if joint.type not in types or not np.allclose(joint.axis, axis):
            raise InputError.single(
                str(urdf.path), joint.line,
                f"--mobile holonomic: joint '{joint.name}' must be the {label} joint, {kind} "
                f"with axis {' '.join(f'{a:g}' for a in axis)}; it is {joint.type or 'untyped'} "
                f"with axis {' '.join(f'{a:g}' for a in joint.axis)} ({want}, root first)",
            )
        if not np.allclose(joint.rpy, 0.0):
            raise InputError.single(
                str(urdf.path), joint.line,
                f"--mobile holonomic: joint '{joint.name}' has a rotated origin (rpy "
                f"{' '.join(f'{a:g}' for a in joint.rpy)}); the virtual joints move along the "
                "root frame's axes, so their origins must not rotate",
            )
    return above


def init_descriptor(opts: InitOptions, notes: list[str] | None = None) -> RobotDescription:
    """Write the descriptor ``opts.out`` for ``opts.urdf`` and return it loaded and checked.

    Raises :class:`~bt_manip.errors.InputError` (file and line of each problem) when the URDF
    does not parse, names are unknown, the tip is not below the base link, a finger joint is not
    prismatic/revolute, meshes are missing, or the written descriptor does not load. Nothing is
    left at ``opts.out`` on failure.
    """
    if not opts.urdf.is_file():
        raise InputError.single(str(opts.urdf), None, "URDF file not found")
    urdf = _Urdf(opts.urdf)
    name = opts.name or opts.out.stem
    if not name or len(name) > MAX_NAME or not all(c.isalnum() or c in "_-" for c in name):
        raise InputError.single(
            str(opts.out), None,
            f"robot name {name!r}: use 1..{MAX_NAME} letters, digits, '_' or '-'",
        )
    movable = [j.name for j in urdf.joints.values() if j.type in ("prismatic", "revolute")]
    gripper, explicit, unmatched = expand_joint_patterns(opts.gripper, movable)
    if unmatched:
        raise InputError.single(
            str(opts.urdf), 1, f"--gripper: no joint matches {', '.join(unmatched)}"
        )
    opts = dataclasses.replace(opts, gripper=tuple(gripper))
    problems = _check_names(urdf, opts)
    if problems:
        raise InputError(problems)
    virtual = holonomic_joints(urdf, opts.base_link) if opts.mobile == "holonomic" else []
    chain = urdf.chain(opts.base_link, opts.arm_tip)
    if chain is None:
        raise InputError.single(
            str(opts.urdf),
            urdf.links.get(opts.arm_tip),
            f"--arm-tip: link '{opts.arm_tip}' is not below --base-link '{opts.base_link}' "
            "(no chain of joints leads from the base link down to it)",
        )
    arm = [j for j in chain if j.type in MOVABLE]
    if not arm:
        raise InputError.single(
            str(opts.urdf), urdf.links.get(opts.arm_tip),
            f"no movable joint between '{opts.base_link}' and '{opts.arm_tip}'",
        )
    in_arm = {j.name for j in arm}
    clash = [g for g in opts.gripper if g in in_arm]
    if clash:
        raise InputError.single(
            str(opts.urdf), urdf.joints[clash[0]].line,
            f"--gripper: joint '{clash[0]}' is part of the arm chain",
        )
    # the composed file checks every mesh (missing files reported with their line)
    composed = composed_urdf(opts.urdf)
    said: list[str] = [] if notes is None else notes
    text = _descriptor_text(urdf, opts, name, arm, composed, virtual, explicit, said)
    return _write_checked(opts.out, text)


def _descriptor_text(
    urdf: _Urdf,
    opts: InitOptions,
    name: str,
    arm: list[_Joint],
    composed: Path,
    virtual: list[_Joint],
    explicit: set[str],
    notes: list[str],
) -> str:
    lower = [j.lower for j in arm]
    upper = [j.upper for j in arm]
    zero = [min(max(0.0, lo), hi) for lo, hi in zip(lower, upper, strict=True)]
    ready = [
        (lo + hi) / 2.0 if math.isfinite(lo) and math.isfinite(hi) else z
        for lo, hi, z in zip(lower, upper, zero, strict=True)
    ]
    velocities = [j.velocity if j.velocity and j.velocity > 0 else DEFAULT_VELOCITY for j in arm]
    efforts = [j.effort if j.effort and j.effort > 0 else None for j in arm]
    geometry = _Geometry(composed, urdf, opts, arm, virtual, explicit)
    notes += geometry.notes
    uri = urdf_uri(opts.urdf, opts.out.parent)
    lines = [
        f"# {name}: written by `bt-manip robot init` from {Path(uri).name}.",
        "# Format: robots/README.md.",
        f"name: {name}",
        "urdf:",
        f"  base: {uri}",
    ]
    if geometry.dropped:
        lines.append(f"  drop_links: [{', '.join(geometry.dropped)}]   # box around the hand")
    if geometry.frictionless:
        lines.append("  contacts:                # passive wheels and casters roll freely")
        lines += [
            f"    {link}: {{lateral_friction: 0.0, rolling_friction: 0.0, "
            "spinning_friction: 0.0}"
            for link in geometry.frictionless
        ]
    if opts.mobile in ("skid", "diff"):
        lines += geometry.mobile_base_lines()
    elif virtual:
        lines += geometry.holonomic_base_lines(virtual)
    else:
        lines += ["base:", "  type: fixed"]
    lines += [
        "arm:",
        f"  base_link: {opts.base_link}",
        f"  joints: [{', '.join(j.name for j in arm)}]",
        f"  velocity_limits: {_vector(velocities)}",
    ]
    if all(e is not None for e in efforts):
        lines.append(f"  efforts: {_vector([e for e in efforts if e is not None])}")
    lines += [
        f"end_effector: {opts.arm_tip}",
        f"grasp_frame: {opts.grasp_frame or opts.arm_tip}",
    ]
    if geometry.axis != "z":
        lines.append(f"approach_axis: {geometry.axis}   # of the grasp frame, measured")
    if geometry.gripper is not None:
        lines += _gripper_lines(geometry.gripper)
    lines += [
        "states:                  # rad, arm joint order, within the joint limits",
        f"  home: {_state(ready, lower, upper)}    # = ready",
        f"  tuck: {_state(zero, lower, upper)}    # = zero",
        f"  zero: {_state(zero, lower, upper)}",
        f"  ready: {_state(ready, lower, upper)}   # middle of each joint's range",
    ]
    lines += geometry.footprint_lines()
    if opts.lidar:
        notes.append(f"the laser at the origin of '{opts.lidar}', scanning in its x-y plane "
                     "(270 deg, 541 beams, 12 m: the sensor defaults of robots/README.md); set "
                     "xyz and rpy in sensors: if it sits elsewhere")
        lines += [
            "sensors:                  # format: robots/README.md (unset keys: the defaults)",
            "  - type: lidar2d",
            "    name: laser",
            f"    link: {opts.lidar}",
            "    xyz: [0.0, 0.0, 0.0]",
            "    rpy: [0.0, 0.0, 0.0]",
        ]
    return "\n".join(lines) + "\n"


def _gripper_lines(g: GripperSurvey) -> list[str]:
    lines = ["gripper:"]
    if g.kind != "parallel":
        lines.append(f"  kind: {g.kind}")
    lines += [
        f"  joints: [{', '.join(g.joints)}]",
        f"  finger_links: [{', '.join(g.finger_links)}]",
    ]
    if g.kind == "parallel":
        lines += [
            f"  open: {_fmt(g.opens[0])}        # finger joint upper limit",
            f"  closed: {_fmt(g.closeds[0])}      # finger joint lower limit",
        ]
    else:
        lines += [
            f"  open: {_vector(list(g.opens))}     # the limit farther from the grasp frame",
            f"  closed: {_vector(list(g.closeds))}   # the limit nearer to it",
            f"  width: {_fmt(g.width)}      # m between the fingers when open (measured)",
        ]
    lines += [f"  max_force: {_fmt(g.max_force)}", f"  max_speed: {_fmt(g.max_speed)}"]
    return lines


class _Geometry:
    """Collision-shape extents of the robot at its zero pose (PyBullet, headless)."""

    def __init__(
        self,
        composed: Path,
        urdf: _Urdf,
        opts: InitOptions,
        arm: list[_Joint],
        virtual: list[_Joint],
        explicit: set[str] | None = None,
    ) -> None:
        import pybullet as pb

        from bt_manip.sim import pybullet_queries as pbq

        self.opts = opts
        self.notes: list[str] = []
        self.dropped: list[str] = []
        self.frictionless: list[str] = []
        self.axis = "z"
        self.gripper: GripperSurvey | None = None
        moved = urdf.below(arm[0].child)
        for g in opts.gripper:
            moved |= urdf.below(urdf.joints[g].child)
        client = pb.connect(pb.DIRECT)
        try:
            try:
                body = pb.loadURDF(str(composed), useFixedBase=True, physicsClientId=client)
            except pb.error:
                raise InputError.single(
                    str(opts.urdf), None, "PyBullet cannot load this URDF (check links and meshes)"
                ) from None
            why = pbq.too_many_links(client, body)
            if why is not None:
                raise InputError.single(str(opts.urdf), None, why)
            names = {-1: pbq.root_link_name(client, body)}
            infos = pbq.joint_infos(client, body)
            for info in infos:
                names[info.index] = info.link_name
            self.base_boxes: list[tuple[np.ndarray, np.ndarray]] = []
            self.all_min = np.full(3, np.inf)
            self.mass = sum(
                float(pb.getDynamicsInfo(body, i, physicsClientId=client)[0]) for i in names
            )
            self.origin = np.zeros(3)
            """Where the footprint is measured from: the root frame, or a holonomic base's
            base link (the yaw joint's child) with its joints at 0."""
            if virtual:
                yaw_index = next(i.index for i in infos if i.name == virtual[2].name)
                self.origin = np.asarray(
                    pb.getLinkState(body, yaw_index, physicsClientId=client)[4], dtype=float
                )
            joint_index = {info.name: info.index for info in infos}
            self._survey_hand(client, body, names, joint_index, urdf, opts, explicit or set())
            skipped = []
            for index, link in names.items():
                lo, hi = pb.getAABB(body, index, physicsClientId=client)
                lo_a, hi_a = np.asarray(lo), np.asarray(hi)
                if link not in urdf.shaped or link in self.dropped:
                    # PyBullet gives a link without a shape a +-1 mm box: not an outline
                    if link not in moved and np.any(hi_a - lo_a > 1e-6):
                        skipped.append(link)
                    continue
                self.all_min = np.minimum(self.all_min, lo_a)
                if link not in moved:
                    self.base_boxes.append((lo_a, hi_a))
            self.wheels: list[tuple[str, float, float]] = []  # joint, y, radius
            wheel_max: list[float] = []
            wheel_effort: list[float] = []
            if opts.mobile in ("skid", "diff"):
                for info in infos:
                    joint = urdf.joints.get(info.name)
                    if joint is None or joint.type != "continuous" or joint.child in moved:
                        continue
                    lo, hi = pb.getAABB(body, info.index, physicsClientId=client)
                    pos = pb.getLinkState(body, info.index, physicsClientId=client)[4]
                    # the URDF's own radius where it has one: PyBullet's box is a few mm larger
                    radius = _rolling_radius(urdf, joint) or (hi[2] - lo[2]) / 2.0
                    if radius <= 0.0:
                        continue
                    self.wheels.append((info.name, float(pos[1]), float(radius)))
                    if joint.velocity:
                        wheel_max.append(joint.velocity)
                    if joint.effort:
                        wheel_effort.append(joint.effort)
            self.wheel_speed = min(wheel_max, default=DEFAULT_WHEEL_SPEED)
            self.wheel_torque = min(wheel_effort, default=DEFAULT_WHEEL_TORQUE)
            if opts.mobile in ("skid", "diff"):
                self._passive_contacts(pb, client, body, names, urdf, moved)
            self._note_footprint(skipped)
        finally:
            pb.disconnect(client)

    def _note_footprint(self, skipped: list[str]) -> None:
        if skipped:
            shown = ", ".join(skipped[:6]) + (", ..." if len(skipped) > 6 else "")
            self.notes.append(
                f"footprint: {len(skipped)} link(s) without a collision shape left out "
                f"({shown}): PyBullet gives each a 1 mm box, not a part of the outline"
            )

    def _passive_contacts(
        self, pb: Any, client: int, body: int, names: dict[int, str], urdf: _Urdf,
        moved: set[str],
    ) -> None:
        """Keep the driven wheels (for a diff drive, the largest on each side); give the other
        wheels and every other link resting on the floor (casters) frictionless contact."""
        if self.opts.mobile == "diff":
            driven = []
            for side in (1.0, -1.0):
                mine = [w for w in self.wheels if w[1] * side > 1e-6]
                biggest = max((w[2] for w in mine), default=0.0)
                driven += [w for w in mine if w[2] >= biggest - 1e-4]
            passive = [w for w in self.wheels if w not in driven]
            self.wheels = driven
            for w in passive:
                self.notes.append(f"base: '{w[0]}' is a passive wheel (smaller than the driven "
                                  "one on its side): frictionless, not driven")
        wheel_links = {urdf.joints[w[0]].child for w in self.wheels}
        floor = float(self.all_min[2])
        for index, link in names.items():
            if link in wheel_links or link in moved or link not in urdf.shaped:
                continue
            below = urdf.below(link)
            if any(urdf.joints[w[0]].child in below for w in self.wheels):
                continue  # a link that carries a driven wheel (the chassis)
            lo, _ = pb.getAABB(body, index, physicsClientId=client)
            if lo[2] <= floor + CASTER_GAP:
                self.frictionless.append(link)
        if self.frictionless:
            self.notes.append(
                f"base: {', '.join(self.frictionless)} rest on the floor beside the driven "
                "wheels (casters or passive wheels): written with frictionless contact "
                "(urdf.contacts), so they roll instead of dragging"
            )

    def _survey_hand(
        self, client: int, body: int, names: dict[int, str], joint_index: dict[str, int],
        urdf: _Urdf, opts: InitOptions, explicit: set[str],
    ) -> None:
        """The gripper, the approach axis and any box enclosing the grasp frame."""
        link_index = {name: index for index, name in names.items()}
        robot = Body(client, body, link_index, joint_index, urdf.below,
                     lambda n: n in urdf.shaped)
        grasp = opts.grasp_frame or opts.arm_tip
        shaped_fingers: set[str] = set()
        for g in opts.gripper:
            shaped_fingers |= {n for n in urdf.below(urdf.joints[g].child) if n in urdf.shaped}
        if opts.approach_axis:
            self.axis = opts.approach_axis
            self.notes.append(f"approach axis {self.axis} of '{grasp}' (given)")
        else:
            self.axis, how = approach_axis(robot, grasp, opts.arm_tip, sorted(shaped_fingers))
            self.notes.append(how)
        turn = rpy_matrix(*APPROACH_AXES[self.axis])
        direction = robot.frame(grasp)[1] @ turn[:, 2]
        if opts.gripper:
            try:
                self.gripper = survey_gripper(
                    robot, urdf.joints, urdf.mimics, opts.gripper, explicit, grasp, direction
                )
            except SurveyError as exc:
                first = urdf.joints.get(opts.gripper[0])
                raise InputError.single(
                    str(urdf.path), first.line if first else None, f"--gripper: {exc}"
                ) from None
            self.notes += self.gripper.notes
            keep = set(self.gripper.finger_links) | shaped_fingers
            self.dropped = enclosing_leaf_links(robot, grasp, urdf.leaves(), keep)
            for link in self.dropped:
                self.notes.append(
                    f"'{link}' is a collision box around the grasp frame (a planning safety "
                    "box): it would hold every object off the fingers, so it is left out "
                    "(urdf.drop_links)"
                )

    def mobile_base_lines(self) -> list[str]:
        left = [w for w in self.wheels if w[1] > 1e-6]
        right = [w for w in self.wheels if w[1] < -1e-6]
        if not left or not right:
            raise InputError.single(
                str(self.opts.urdf), None,
                f"--mobile {self.opts.mobile}: found no continuous wheel joints on both sides "
                f"of the root link (left: {[w[0] for w in left]}, right: {[w[0] for w in right]})",
            )
        track = float(np.mean([w[1] for w in left]) - np.mean([w[1] for w in right]))
        radius = float(np.mean([w[2] for w in self.wheels]))
        return [
            f"spawn_height: {_fmt(max(0.0, -float(self.all_min[2])))}   # wheels on the floor",
            "base:",
            "  type: skid_steer",
            f"  left_wheels: [{', '.join(w[0] for w in left)}]",
            f"  right_wheels: [{', '.join(w[0] for w in right)}]",
            f"  wheel_radius: {_fmt(radius)}",
            f"  track_width: {_fmt(track)}   # geometric; measure the effective one for skid-steer",
            f"  max_wheel_speed: {_fmt(self.wheel_speed)}",
            f"  wheel_max_torque: {_fmt(self.wheel_torque)}",
        ]

    def holonomic_base_lines(self, virtual: list[_Joint]) -> list[str]:
        x, y, yaw = virtual
        speeds = [j.velocity for j in (x, y) if j.velocity and j.velocity > 0]
        speed = min(min(speeds, default=HOLONOMIC_SPEED), 5.0)
        yaw_rate = min(yaw.velocity if yaw.velocity and yaw.velocity > 0 else HOLONOMIC_YAW_RATE,
                       10.0)
        efforts = [j.effort for j in (x, y) if j.effort and j.effort > 0]
        weight_push = PUSH_FRICTION * 9.81 * max(self.mass, 1.0)
        force = min(min(efforts, default=weight_push), 1e5)
        lo, hi = self._base_extent()
        reach = max(0.1, float(np.hypot(np.maximum(abs(lo), abs(hi))[0],
                                        np.maximum(abs(lo), abs(hi))[1])))
        torque = min(yaw.effort if yaw.effort and yaw.effort > 0 else force * reach, 1e5)
        height = max(0.0, -float(self.all_min[2])) + FLOOR_GAP
        return [
            f"spawn_height: {_fmt(height)}   # the base {FLOOR_GAP * 100:g} cm clear of the floor",
            "base:                     # virtual joints x, y, yaw; the root is fixed at spawn",
            "  type: holonomic",
            f"  joints: [{x.name}, {y.name}, {yaw.name}]",
            f"  max_speed: {_fmt(speed)}        # m/s",
            f"  max_yaw_rate: {_fmt(yaw_rate)}     # rad/s",
            f"  max_accel: {_fmt(HOLONOMIC_ACCEL)}        # m/s^2, path follower",
            "  max_yaw_accel: 2.0     # rad/s^2, path follower",
            f"  max_force: {_fmt(force)}       # N per planar joint motor",
            f"  max_torque: {_fmt(torque)}      # N m, yaw joint motor",
        ]

    def _base_extent(self) -> tuple[np.ndarray, np.ndarray]:
        """Lower and upper corners of the base links' boxes, relative to :attr:`origin`."""
        if not self.base_boxes:
            return np.full(3, -0.1), np.full(3, 0.1)
        lo = np.min([b[0] for b in self.base_boxes], axis=0) - self.origin
        hi = np.max([b[1] for b in self.base_boxes], axis=0) - self.origin
        return lo, hi

    def footprint_lines(self) -> list[str]:
        if not self.base_boxes:
            return ["footprint:                # no collision shape off the arm", "  radius: 0.1"]
        lo, hi = self._base_extent()
        if self.opts.mobile == "holonomic":
            return [
                "footprint:                # around the base links' collision shapes",
                f"  length: {_fmt(max(hi[0] - lo[0], 0.01))}",
                f"  width: {_fmt(max(2.0 * max(abs(hi[1]), abs(lo[1])), 0.01))}",
                f"  x_offset: {_fmt((hi[0] + lo[0]) / 2.0)}",
            ]
        if self.opts.mobile in ("skid", "diff"):
            return [
                "footprint:                # around the base links' collision shapes",
                f"  length: {_fmt(max(hi[0] - lo[0], 0.01))}",
                f"  width: {_fmt(max(hi[1] - lo[1], 0.01))}",
                f"  x_offset: {_fmt((hi[0] + lo[0]) / 2.0)}",
            ]
        corners = [math.hypot(x, y) for x in (lo[0], hi[0]) for y in (lo[1], hi[1])]
        return [
            "footprint:                # circle around the collision shapes no arm joint moves",
            f"  radius: {_fmt(max(max(corners), 0.01))}",
        ]


def _write_checked(out: Path, text: str) -> RobotDescription:
    """Write ``text`` beside ``out``, load it as a world would, and move it to ``out`` if good."""
    out.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp_name = tempfile.mkstemp(prefix=f".{out.stem}-", suffix=".yaml", dir=out.parent)
    tmp = Path(tmp_name)
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as fh:
            fh.write(text)
        desc = load_description(tmp)
        _check_kinematics(desc)
        os.replace(tmp, out)
    finally:
        tmp.unlink(missing_ok=True)
    return load_description(out)


def _check_kinematics(desc: RobotDescription) -> None:
    from bt_manip.kinematics.arm_model import ArmModel, KinematicsError

    try:
        ArmModel.from_urdf(desc.urdf_path, base_link=desc.arm.base_link, tip_link=desc.end_effector)
    except (KinematicsError, ValueError, RuntimeError, IndexError) as exc:
        raise InputError.single(
            str(desc.path), None, f"the arm model does not build: {exc}"
        ) from None
