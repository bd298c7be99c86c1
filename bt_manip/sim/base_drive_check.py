"""Driving a mobile base at a set speed and measuring what it achieves, for ``robot check``.

:func:`drive_and_turn` drives a skid-steer or holonomic base 2 m straight at 0.5 m/s, then a
quarter turn on the spot at 1 rad/s (each clipped to what the base can do), through
:meth:`~bt_manip.sim.robot.Robot.set_base_twist`, in sim time. The achieved speed of a move is
the distance (or yaw) covered over its steady part, after the first :data:`SETTLE_S` of
acceleration, divided by that part's duration. Over the steady part it also samples what could
hold the base back: the robot's links other than the driven wheels that drag on the floor (with
their normal and friction forces), the wheels' own speed and motor torque (skid-steer), or the
virtual joints' motor effort (holonomic). :func:`explain` turns a slow move into one line of plain
words naming the likeliest cause.

PyBullet reports a contact on the link that carries a collision shape; a link on a ``fixed``
joint may have been folded into its parent (:mod:`bt_manip.sim.fixed_links`), so a contact on
such a carrier is put to the nearest of the carrier and the folded links with collision shapes
(nearest link frame to the contact point).
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from dataclasses import dataclass

import pybullet as pb

from bt_manip.sim import pybullet_queries as pbq
from bt_manip.sim.robot import Robot, composed_urdf

__all__ = ["BaseMove", "FloorContact", "drive_and_turn", "explain"]

RATE_HZ = 240
DRIVE_DISTANCE = 2.0
"""m driven straight."""
DRIVE_SPEED = 0.5
"""m/s asked for the straight drive (less when the base is slower)."""
TURN_ANGLE = math.pi / 2.0
"""rad turned on the spot."""
TURN_RATE = 1.0
"""rad/s asked for the turn (less when the base is slower)."""
SETTLE_S = 0.5
"""s of acceleration left out of the measured part of each move."""
MIN_FRACTION = 0.8
"""A move passes when it achieves at least this fraction of the commanded speed."""
COMMAND_EVERY = RATE_HZ // 20
"""Steps between two twist commands (a controller's 20 Hz)."""
SAMPLE_EVERY = 4
"""Steps between two samples of contacts and motors."""
CONTACT_SHARE = 0.1
"""A link counts as touching the floor when it does in at least this share of the samples."""
DRAG_MIN = 1.0
"""N of mean friction force from which a link touching the floor drags (a frictionless caster
carries weight but does not)."""
WHEELS_TURN = 0.9
"""Wheels turning at this fraction of their commanded speed or more turn as commanded."""
AT_LIMIT = 0.95
"""A motor at this fraction of its torque (force) limit or more is at its limit."""
README = "robots/README.md"


@dataclass(frozen=True)
class FloorContact:
    """A link other than the driven wheels that touched the floor during a move."""

    link: str
    kind: str
    """Type of the joint above the link in the URDF (``fixed``, ``continuous``, ...; ``root``)."""
    force: float
    """N: normal force, averaged over the samples of the steady part."""
    drag: float
    """N: friction force, averaged likewise."""
    share: float
    """Share of the samples in which it touched."""


@dataclass(frozen=True)
class BaseMove:
    """One measured base move: ``drive`` (m/s) or ``turn`` (rad/s)."""

    phase: str
    commanded: float
    achieved: float
    time_s: float
    contacts: tuple[FloorContact, ...] = ()
    """The links other than the driven wheels that dragged on the floor, heaviest first."""
    wheel_rate: float | None = None
    """Skid-steer: the speed (drive, m/s) or yaw rate (turn, rad/s) the wheels' own mean speeds
    give through ``wheel_radius`` and ``track_width``; None for a holonomic base."""
    effort: float = 0.0
    """Mean motor effort of the wheels (skid-steer) or of the moving virtual joint (holonomic),
    as a fraction of its limit."""
    weight: float = 0.0
    """N: the robot's weight."""

    @property
    def unit(self) -> str:
        return "m/s" if self.phase == "drive" else "rad/s"

    @property
    def ok(self) -> bool:
        return self.achieved >= MIN_FRACTION * self.commanded


def top_speeds(robot: Robot) -> tuple[float, float]:
    """Largest forward speed (m/s) and yaw rate on the spot (rad/s) the base allows."""
    base = robot.description.base
    if robot.is_holonomic:
        return base.max_speed, base.max_yaw_rate
    rim = base.max_wheel_speed * base.wheel_radius
    return rim, 2.0 * rim / base.track_width


def drive_and_turn(client: int, robot: Robot, floor: int) -> list[BaseMove]:
    """Drive the base straight, then turn it on the spot; one :class:`BaseMove` each. The base
    is braked after each move."""
    top_v, top_w = top_speeds(robot)
    kinds = _link_kinds(robot)
    weight = 9.81 * sum(
        pbq.dynamics_info(client, robot.body, link).mass
        for link in range(-1, pb.getNumJoints(robot.body, physicsClientId=client))
    )
    moves = []
    for phase, speed, goal in (
        ("drive", min(DRIVE_SPEED, top_v), DRIVE_DISTANCE),
        ("turn", min(TURN_RATE, top_w), TURN_ANGLE),
    ):
        moves.append(_move(client, robot, floor, kinds, phase, speed, goal, weight))
        _step(client, round(SETTLE_S * RATE_HZ))
    return moves


def _move(
    client: int,
    robot: Robot,
    floor: int,
    kinds: dict[str, tuple[str, bool]],
    phase: str,
    speed: float,
    goal: float,
    weight: float,
) -> BaseMove:
    twist = (speed, 0.0) if phase == "drive" else (0.0, speed)
    limit = round((2.0 * goal / max(speed, 1e-3) + 2.0) * RATE_HZ)
    skip = round(SETTLE_S * RATE_HZ)
    start = robot.base_pose2d()
    yaw = start[2]
    progress = 0.0
    mark = (0.0, 0)
    samples = _Samples()
    steps = 0
    while steps < limit:
        if steps % COMMAND_EVERY == 0:
            robot.set_base_twist(*twist)
        pb.stepSimulation(physicsClientId=client)
        steps += 1
        x, y, now = robot.base_pose2d()
        if phase == "drive":
            progress = math.hypot(x - start[0], y - start[1])
        else:
            progress += math.remainder(now - yaw, 2.0 * math.pi)
            yaw = now
        if steps == skip:
            mark = (progress, steps)
        elif steps > skip and steps % SAMPLE_EVERY == 0:
            samples.take(robot, floor, kinds, phase)
        if progress >= goal:
            break
    robot.stop_base()
    if steps - mark[1] < RATE_HZ // 4:  # reached before the steady part: use the whole move
        mark = (0.0, 0)
    achieved = (progress - mark[0]) / ((steps - mark[1]) / RATE_HZ)
    return BaseMove(
        phase, speed, achieved, steps / RATE_HZ, samples.contacts(kinds),
        samples.wheel_rate(robot, phase), samples.effort(), weight,
    )


class _Samples:
    """What was seen at each sample of a move's steady part."""

    def __init__(self) -> None:
        self.n = 0
        self.force: dict[str, float] = {}
        self.drag: dict[str, float] = {}
        self.seen: dict[str, int] = {}
        self.left = 0.0
        self.right = 0.0
        self.effort_sum = 0.0

    def take(
        self, robot: Robot, floor: int, kinds: dict[str, tuple[str, bool]], phase: str
    ) -> None:
        self.n += 1
        wheels = set(robot.wheel_ids_left + robot.wheel_ids_right)
        touching: set[str] = set()
        for c in pbq.contacts(robot.client, robot.body, floor):
            if c.link_a in wheels:
                continue
            name = _attribute(robot, c.link_a, c.position_on_a, kinds)
            self.force[name] = self.force.get(name, 0.0) + c.normal_force
            friction = math.hypot(c.lateral_friction_1, c.lateral_friction_2)
            self.drag[name] = self.drag.get(name, 0.0) + friction
            touching.add(name)
        for name in touching:
            self.seen[name] = self.seen.get(name, 0) + 1
        base = robot.description.base
        if robot.has_wheels:
            ids = robot.wheel_ids_left + robot.wheel_ids_right
            states = pbq.joint_states(robot.client, robot.body, ids)
            n_left = len(robot.wheel_ids_left)
            left, right = states[:n_left], states[n_left:]
            self.left += sum(s.velocity for s in left) / len(left)
            self.right += sum(s.velocity for s in right) / len(right)
            torque = sum(abs(s.applied_torque) for s in states) / len(states)
            self.effort_sum += torque / max(base.wheel_max_torque, 1e-9)
        elif robot.is_holonomic:
            states = pbq.joint_states(robot.client, robot.body, robot.base_joint_ids)
            if phase == "drive":
                self.effort_sum += abs(states[0].applied_torque) / max(base.max_force, 1e-9)
            else:
                self.effort_sum += abs(states[2].applied_torque) / max(base.max_torque, 1e-9)

    def contacts(self, kinds: dict[str, tuple[str, bool]]) -> tuple[FloorContact, ...]:
        n = max(self.n, 1)
        found = [
            FloorContact(
                name, kinds.get(name, ("fixed", True))[0], self.force[name] / n,
                self.drag[name] / n, seen / n,
            )
            for name, seen in self.seen.items()
            if seen / n >= CONTACT_SHARE and self.drag[name] / n >= DRAG_MIN
        ]
        return tuple(sorted(found, key=lambda c: -c.force))

    def wheel_rate(self, robot: Robot, phase: str) -> float | None:
        if not robot.has_wheels or self.n == 0:
            return None
        base = robot.description.base
        left, right = self.left / self.n, self.right / self.n
        if phase == "drive":
            return base.wheel_radius * (left + right) / 2.0
        return base.wheel_radius * (right - left) / base.track_width

    def effort(self) -> float:
        return self.effort_sum / max(self.n, 1)


def _attribute(
    robot: Robot,
    index: int,
    point: tuple[float, ...],
    kinds: dict[str, tuple[str, bool]],
) -> str:
    """The URDF link a contact on PyBullet link ``index`` at ``point`` is on: the link itself,
    or the nearest of the fixed links folded into it that have collision shapes."""
    own = robot.link_name(index)
    names = [own] + [n for n, (carrier, _) in robot.merged_frames.items() if carrier == index]
    shaped = [n for n in names if kinds.get(n, ("", True))[1]]
    if len(shaped) <= 1:
        return shaped[0] if shaped else own
    return min(shaped, key=lambda n: math.dist(point, robot.link_pose(n)[0].tolist()))


def _link_kinds(robot: Robot) -> dict[str, tuple[str, bool]]:
    """Each URDF link of the robot: the type of the joint above it (``root`` for the root) and
    whether it has a collision shape."""
    root = ET.parse(composed_urdf(robot.description)).getroot()
    above = {}
    for joint in root.findall("joint"):
        child = joint.find("child")
        if child is not None:
            above[child.get("link", "")] = joint.get("type", "fixed")
    return {
        link.get("name", ""): (
            above.get(link.get("name", ""), "root"), link.find("collision") is not None
        )
        for link in root.findall("link")
    }


def explain(move: BaseMove, robot: Robot) -> str:
    """One line: how slow ``move`` was and the likeliest cause, in plain words."""
    percent = 100.0 * move.achieved / max(move.commanded, 1e-9)
    head = (
        f"base {move.phase}: {_num(move.achieved)} {move.unit} of "
        f"{_num(move.commanded)} {move.unit} commanded ({percent:.0f} %)"
    )
    if move.contacts:
        return f"{head}: {_touching(move, robot)}"
    return f"{head}: nothing but the driven wheels drags on the floor; {_motors(move, robot)}"


def _touching(move: BaseMove, robot: Robot) -> str:
    names = ", ".join(c.link for c in move.contacts)
    force = sum(c.force for c in move.contacts)
    drag = sum(c.drag for c in move.contacts)
    kinds = {c.kind for c in move.contacts}
    if len(kinds) == 1:
        (kind,) = kinds
        what = "the root link" if kind == "root" else f"{kind} links"
    else:
        what = "links on " + ", ".join(sorted(kinds)) + " joints"
    verb = "touches" if len(move.contacts) == 1 else "touch"
    share = f" of the robot's {move.weight:.0f} N weight" if robot.has_wheels else ""
    return (
        f"{names} {verb} the floor ({what} carrying {force:.0f} N{share}, dragging with "
        f"{drag:.0f} N); give passive wheels "
        f"and casters frictionless contact in the descriptor's contacts: section ({README})"
    )


def _motors(move: BaseMove, robot: Robot) -> str:
    base = robot.description.base
    if move.wheel_rate is None:  # holonomic
        if move.effort >= AT_LIMIT:
            limit = "max_force" if move.phase == "drive" else "max_torque"
            return (
                f"the base's motors push at their limit ({limit}); raise {limit} in the "
                f"URDF's joint effort or lighten the load ({README})"
            )
        return (
            f"the base's motors use {100.0 * move.effort:.0f} % of their limit; check the "
            f"virtual joints' speed limits and damping in the URDF"
        )
    wheels = f"{_num(move.wheel_rate)} {move.unit}"
    torque = f"wheel_max_torque {base.wheel_max_torque:g} N m"
    if move.wheel_rate >= WHEELS_TURN * move.commanded:
        if move.phase == "turn":
            return (
                f"the wheels turn for {wheels} (with track_width {base.track_width:g} m) but "
                f"the base turns slower: they slip sideways, or the effective track_width is "
                f"wider; measure it turning on the spot, or lower wheel_axle_friction_scale "
                f"({README})"
            )
        return (
            f"the wheels turn for {wheels} but the base moves slower: they slip "
            f"(wheel_friction {base.wheel_friction:g}; check the wheels' contact in the "
            f"descriptor's contacts: section, {README})"
        )
    if move.effort >= AT_LIMIT:
        return (
            f"the wheels turn for only {wheels}, their motors at {torque}: raise it, or "
            f"lighten the robot"
        )
    return (
        f"the wheels turn for only {wheels}, their motors at {100.0 * move.effort:.0f} % of "
        f"{torque}: check max_wheel_speed and the wheel joints' damping and friction"
    )


def _num(value: float) -> str:
    """``value`` to two decimals, never ``-0.00``."""
    return f"{round(value, 2) + 0.0:.2f}"


def _step(client: int, n: int) -> None:
    for _ in range(n):
        pb.stepSimulation(physicsClientId=client)
