"""``bt-manip robot check``: does a described robot move as its descriptor says?

:func:`check_robot` spawns the robot alone in an empty headless PyBullet world (a floor for
mobile bases, none for fixed arms; friction as in every bt-manip world), puts the arm in its
``home`` state, then moves each arm joint in turn to its lower limit, its upper limit (each less
a margin) and back, in sim time with the robot's own position controllers. A move passes when
the joint settles within the tolerance of its target before a time-out computed from the
joint's speed limit. The gripper, when there is one, must open to its full opening and close
again. A holonomic base then drives a 0.3 m square (x, then y, then back) and turns a quarter
turn and back, through :meth:`~bt_manip.sim.robot.Robot.set_base_velocity`; each move is one
row of its virtual joint.

Last, every base that is not fixed (skid-steer or holonomic) drives 2 m straight at 0.5 m/s and
turns a quarter turn on the spot at 1 rad/s, each clipped to the base's own top speed, through
:meth:`~bt_manip.sim.robot.Robot.set_base_twist` (:mod:`bt_manip.sim.base_drive_check`). These
are the rows ``base drive`` and ``base turn``: their target is the commanded speed (m/s, rad/s)
and what they reach the speed achieved over the steady part of the move (its first 0.5 s of
acceleration left out), in sim time. A speed row passes when it achieves at least 80 % of the
commanded speed. For each one that does not, :attr:`CheckReport.causes` holds a line of plain
words: the links other than the driven wheels that touch the floor and the force they carry
(casters that drag: give them frictionless contact in the descriptor's ``contacts:`` section),
or, when nothing else touches, what the wheels did (they turned as commanded and slipped, or
their motors were at their torque limit).

The result is a table (:meth:`CheckReport.table`), the causes, and ``ok`` (every row passed).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import pybullet as pb

from bt_manip.sim.base_drive_check import MIN_FRACTION, drive_and_turn, explain
from bt_manip.sim.robot import Robot
from bt_manip.sim.robot_description import RobotDescription

__all__ = ["CheckReport", "MoveResult", "check_robot"]

RATE_HZ = 240
MARGIN_FRACTION = 0.02
MARGIN_MIN = 0.02
TOLERANCE = 0.02
"""rad (or m) a joint may end from its target."""
GRIPPER_TOLERANCE = 0.004
"""m the pad opening may end from the commanded one."""
WIDE = 2.0 * math.pi
"""Half range tried for joints without limits."""
NO_LIMIT = 1e3
"""A limit farther out than this (rad or m) counts as none: URDFs written by simulators give
"unlimited" joints +-1e16."""
MOVE_TIMEOUT_S = 60.0
"""Sim seconds a move may take at most, whatever its distance and speed limit."""
SETTLE_S = 1.0
BASE_SQUARE = 0.3
"""m: side of the square a holonomic base drives."""
BASE_GAIN = 2.0
"""1/s: the check's proportional drive of a holonomic base toward each corner."""


@dataclass(frozen=True)
class MoveResult:
    """One commanded move: what was asked, what was reached, and whether it is within tolerance."""

    joint: str
    phase: str
    target: float
    reached: float
    time_s: float
    speed: bool = False
    """A speed row (the base's ``drive`` and ``turn``): target and reached are speeds, and it
    passes when it reaches at least :data:`MIN_FRACTION` of the target."""

    @property
    def ok(self) -> bool:
        if self.speed:
            return self.reached >= MIN_FRACTION * self.target
        tol = GRIPPER_TOLERANCE if self.joint == "gripper" else TOLERANCE
        return abs(self.reached - self.target) <= tol


@dataclass
class CheckReport:
    """Every move of one check run."""

    robot: str
    moves: list[MoveResult] = field(default_factory=list)
    causes: list[str] = field(default_factory=list)
    """One line of plain words for each speed row that failed: why the base was slow."""

    @property
    def ok(self) -> bool:
        return all(m.ok for m in self.moves)

    def table(self) -> str:
        """The moves as an aligned text table, one line per move, and a verdict."""
        width = max([len("joint")] + [len(m.joint) for m in self.moves])
        lines = [f"{'joint':<{width}}  {'move':<6} {'target':>8} {'reached':>8} {'time s':>7}  ok"]
        for m in self.moves:
            lines.append(
                f"{m.joint:<{width}}  {m.phase:<6} {m.target:8.4f} {m.reached:8.4f} "
                f"{m.time_s:7.2f}  {'yes' if m.ok else 'NO'}"
            )
        bad = sum(not m.ok for m in self.moves)
        verdict = "all moves reached" if bad == 0 else f"{bad} of {len(self.moves)} moves missed"
        lines.append(f"{self.robot}: {verdict}")
        return "\n".join(lines)


def _targets(lower: float, upper: float, start: float) -> tuple[float, float]:
    if not abs(lower) <= NO_LIMIT or not abs(upper) <= NO_LIMIT:  # inf, nan or 1e16
        lower, upper = start - WIDE, start + WIDE
        lower = max(lower, -NO_LIMIT)
        upper = min(upper, NO_LIMIT)
    margin = max(MARGIN_MIN, MARGIN_FRACTION * (upper - lower))
    return lower + margin, upper - margin


def check_robot(description: RobotDescription) -> CheckReport:
    """Spawn ``description`` headless and move every joint; see the module docstring."""
    client = pb.connect(pb.DIRECT)
    try:
        pb.setGravity(0, 0, -9.81, physicsClientId=client)
        pb.setTimeStep(1.0 / RATE_HZ, physicsClientId=client)
        # friction as in every bt-manip world (World._setup_physics): a pyramid, not a cone
        pb.setPhysicsEngineParameter(
            enableConeFriction=0, deterministicOverlappingPairs=1, physicsClientId=client
        )
        floor = -1
        if description.base.type != "fixed":
            import pybullet_data

            pb.setAdditionalSearchPath(pybullet_data.getDataPath(), physicsClientId=client)
            floor = pb.loadURDF("plane.urdf", physicsClientId=client)
        robot = Robot.spawn(client, description, 0.0, 0.0, 0.0)
        return _run(client, robot, floor)
    finally:
        pb.disconnect(client)


def _run(client: int, robot: Robot, floor: int) -> CheckReport:
    desc = robot.description
    report = CheckReport(desc.name)
    start = list(desc.state("home"))
    robot.reset_arm(start)
    _step(client, round(SETTLE_S * RATE_HZ))
    velocities = desc.arm.velocity_limits
    for i, name in enumerate(desc.arm.joints):
        lo, hi = _targets(desc.arm.lower[i], desc.arm.upper[i], start[i])
        for phase, value in (("lower", lo), ("upper", hi), ("back", start[i])):
            q = list(start)
            q[i] = value
            here = float(robot.arm_positions()[i])
            timeout = min(abs(value - here) / max(velocities[i], 1e-3) * 2.0 + 2.0,
                          MOVE_TIMEOUT_S)
            robot.set_arm_targets(q)
            took = _until(client, timeout, lambda i=i, v=value: abs(robot.arm_positions()[i] - v))
            report.moves.append(
                MoveResult(name, phase, value, float(robot.arm_positions()[i]), took)
            )
        robot.set_arm_targets(start)
        _step(client, round(0.2 * RATE_HZ))
    g = desc.gripper
    if g.joints:
        moves = (("open", g.max_opening), ("close", g.min_opening), ("open", g.max_opening))
        for phase, opening in moves:
            robot.set_gripper(opening)
            timeout = min(g.stroke_time * 2.0 + 2.0, MOVE_TIMEOUT_S)
            took = _until(client, timeout, lambda o=opening: abs(robot.gripper_opening() - o))
            report.moves.append(
                MoveResult("gripper", phase, opening, robot.gripper_opening(), took)
            )
    if robot.is_holonomic:
        _check_holonomic(client, robot, report)
    if robot.is_holonomic or robot.has_wheels:
        for move in drive_and_turn(client, robot, floor):
            report.moves.append(
                MoveResult("base", move.phase, move.commanded, move.achieved, move.time_s, True)
            )
            if not move.ok:
                report.causes.append(explain(move, robot))
    return report


def _check_holonomic(client: int, robot: Robot, report: CheckReport) -> None:
    """Drive the virtual joints around a square and through a quarter turn, one row each."""
    names = robot.description.base.joints
    base = robot.description.base
    moves = (
        (0, "+", BASE_SQUARE), (1, "+", BASE_SQUARE), (0, "back", 0.0), (1, "back", 0.0),
        (2, "turn", math.pi / 2.0), (2, "back", 0.0),
    )
    goal = [0.0, 0.0, 0.0]
    for axis, phase, value in moves:
        goal[axis] = value
        speed = base.max_yaw_rate if axis == 2 else base.max_speed
        timeout = min(BASE_SQUARE / max(speed, 1e-3) * 3.0 + 3.0, MOVE_TIMEOUT_S)
        took = _drive_base(client, robot, list(goal), timeout)
        reached = float(robot._positions(robot.base_joint_ids)[axis])
        report.moves.append(MoveResult(names[axis], phase, value, reached, took))
    robot.stop_base()


def _drive_base(client: int, robot: Robot, goal: list[float], timeout: float) -> float:
    """Drive the virtual joints to ``goal`` (x, y, yaw) with a proportional base velocity;
    sim seconds taken (``timeout`` at most). The base is braked at the end."""
    steps = 0
    calm = 0
    limit = round(timeout * RATE_HZ)
    while steps < limit:
        q = robot._positions(robot.base_joint_ids)
        ex, ey, ew = goal[0] - q[0], goal[1] - q[1], goal[2] - q[2]
        ex, ey, ew = (_creep(e) for e in (ex, ey, ew))
        c, s = math.cos(q[2]), math.sin(q[2])
        robot.set_base_velocity(c * ex + s * ey, -s * ex + c * ey, ew)
        pb.stepSimulation(physicsClientId=client)
        steps += 1
        if max(abs(ex), abs(ey), abs(ew)) <= TOLERANCE / 4.0:
            calm += 1
            if calm >= RATE_HZ // 10:
                break
        else:
            calm = 0
    robot.stop_base()
    return steps / RATE_HZ


def _creep(error: float) -> float:
    """Proportional speed toward a target, at least 0.05 (m/s or rad/s) until very close."""
    if abs(error) <= TOLERANCE / 8.0:
        return 0.0
    return math.copysign(max(BASE_GAIN * abs(error), 0.05), error)


def _step(client: int, n: int) -> None:
    for _ in range(n):
        pb.stepSimulation(physicsClientId=client)


def _until(client: int, timeout: float, error: object) -> float:
    """Step until ``error()`` stays within tolerance for 0.1 s or ``timeout`` (sim s) passes."""
    assert callable(error)
    calm = 0
    steps = 0
    limit = round(timeout * RATE_HZ)
    while steps < limit:
        pb.stepSimulation(physicsClientId=client)
        steps += 1
        if error() <= TOLERANCE / 4.0:
            calm += 1
            if calm >= RATE_HZ // 10:
                break
        else:
            calm = 0
    return steps / RATE_HZ
