"""Arm behaviours in joint space: one joint at a time, all together, and lifting by deltas.

Each commands the arm's position controllers and returns RUNNING until the joints are within
tolerance; none blocks. Targets outside the joint limits, a joint that does not arrive within
its time-out (sim time), and contact between the arm (or what it carries) and the static world
end the move with FAILURE and a reason; the arm then holds where it is.
"""

from __future__ import annotations

import math
import operator
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from py_trees.common import Status
from py_trees.ports import PortInformation

from bt_manip.behaviours.base import ActionFailed, RobotAction
from bt_manip.behaviours.collisions import arm_collisions
from bt_manip.bt import registry
from bt_manip.bt.ports import NON_NEGATIVE, POSITIVE, Accepts, Port, count_of
from bt_manip.geometry import pose_matrix
from bt_manip.kinematics.reasons import BEYOND_REACH, JOINT_LIMITS, NOT_CONVERGED, SOLVER_KNOBS
from bt_manip.manipulation import cartesian
from bt_manip.manipulation.arm_planner import PLANNERS, ArmPlanner
from bt_manip.manipulation.base_search import object_grasp
from bt_manip.manipulation.collision_scene import named_contacts
from bt_manip.manipulation.rrt_connect import PlanError, check_end, path_length
from bt_manip.manipulation.trajectory import Trajectory, time_parameterise
from bt_manip.sim.randomize import entity_rng

if TYPE_CHECKING:
    from bt_manip.run.context import RobotServices
    from bt_manip.sim.robot import Robot

UNITS = Port(str, False, "unit of targets: deg or rad", "deg", Accepts(choices=("deg", "rad")))
TOLERANCE = Port(float, False, "how close each joint must get (rad)", 0.01, POSITIVE)
SPEED = Port(
    float, False, "fraction of each joint's velocity limit, 0..1", 0.5, Accepts(0, 1, low_open=True)
)
TIMEOUT = Port(float, False, "sim seconds allowed per joint move", 10.0, POSITIVE)
CHECK = PortInformation(bool, False, "fail when the arm touches walls, furniture or floor", True)
SETTLE_SPEED = 0.05
"""A joint counts as arrived when within tolerance and slower than this (rad/s)."""
VIA_TOLERANCE = 0.05
"""A pass-through waypoint counts as reached within this (rad), without stopping there (the
default of the ``via_tolerance`` port of the moves through waypoints)."""
VIA = Port(
    float, False,
    "how close each joint must get to a pass-through waypoint (rad); smaller: the tool keeps "
    "closer to a straight line, and moves slower", VIA_TOLERANCE, POSITIVE,
)
CORRECTION_SPEED = 0.2
"""Every joint may correct at no less than this fraction of its allowed speed."""
IK_GOAL_TRIES = 12
"""Other IK seeds tried when the first solution for a pose is in collision."""
ARM_PATH_COLOUR = (0.95, 0.45, 0.1, 1.0)
"""The colour the viewer and the replay draw a planned arm path in."""
DEFAULT_LOOKAHEAD = 0.05
"""s: how far ahead of now a trajectory's position is given before the second tick (one tick at
the default 20 Hz); from then on, the time since the previous tick."""
MIN_LOOKAHEAD = 0.01
TRACK_MARGIN = 1.25
"""A joint following a trajectory may move this many times the trajectory's speed, to catch up."""
CHECKS_PER_TICK = 4000
"""Collision checks a planning node spends per tick at most (plus one search round)."""
PLANNER = Port(
    str, False, "auto: plan round obstacles when the direct joint move would collide (and pick "
    "a collision-free IK solution); rrtconnect: always plan; none: move directly", "auto",
    Accepts(choices=PLANNERS),
)
PADDING_PORT = Port(
    float, False, "how much the world's shapes grow when a path is planned (m; goals and "
    "straight moves are checked without it); unset: the robot descriptor's planning.padding",
    None,
    Accepts(0, 0.2),
)
PLAN_OUTPUTS: dict[str, PortInformation] = {
    "path_length": PortInformation(float, False, "joint-space length of the move (rad)"),
    "plan_samples": PortInformation(int, False, "samples the planner drew (0: direct move)"),
}


@dataclass
class Stage:
    """One step of a move: the full arm command (rad), the joints it moves, and whether it is
    a pass-through waypoint (reached loosely, without stopping) or a point to stop at."""

    command: np.ndarray
    joints: list[int]
    via: bool = False
    plannable: bool = False
    """A free joint move that may be replaced by a planned, collision-free one."""
    goal_checked: bool = False
    """A plannable stage whose command the node already found free in the planning scene."""
    trajectory: Trajectory | None = None
    """A planned path to this stage's command, timed within the joints' limits: the arm is
    given the trajectory's position a tick ahead, tick after tick, then the command."""


def to_radians(values: list[float], units: str) -> np.ndarray:
    if units not in ("deg", "rad"):
        raise ActionFailed(f"units must be 'deg' or 'rad', got '{units}'")
    a = np.asarray(values, dtype=float)
    return np.radians(a) if units == "deg" else a


def _fmt(q: float, units: str) -> str:
    return f"{math.degrees(q):.1f} deg" if units == "deg" else f"{q:.3f} rad"


class JointMove(RobotAction):
    """Shared machinery: a list of stages, each moving some joints to their targets."""

    CARRIES = True

    INPUT_PORTS: dict[str, PortInformation] = {
        **RobotAction.INPUT_PORTS,
        "units": UNITS,
        "tolerance": TOLERANCE,
        "speed": SPEED,
        "joint_timeout": TIMEOUT,
        "check_collisions": CHECK,
    }

    PLANS = False
    """Whether the node has a ``planner`` port (its plannable stages may be planned)."""
    SWEEPS = False
    """Whether each stage's sweep is checked in the planning scene before the arm moves."""
    LINE_CHECK = False
    """Whether the node's straight moves are checked in the planning scene before it starts."""
    LINE_NAME = "the straight move"
    """How a failed line check names the move."""

    def plan(self, q_now: np.ndarray) -> list[Stage]:
        """The stages of the move."""
        raise NotImplementedError

    def grasping(self) -> str:
        """The object the move goes to grasp ("" for none): allowed to touch the hand."""
        return ""

    def _planner(self) -> ArmPlanner | None:
        """The robot's arm planner, or None when this node does not plan."""
        if not self.PLANS or self.get_input("planner") == "none":
            return None
        return self.arm_planner()

    def _free_goal(
        self, tip: str, pose: np.ndarray, q: np.ndarray, q_now: np.ndarray, free: bool,
        then: Callable[[np.ndarray], list[np.ndarray]] | None = None,
    ) -> tuple[np.ndarray, list[np.ndarray]]:
        """``q`` (IK's answer for ``pose``) when the planning scene finds it free, and the
        straight moves ``then`` makes from it (an approach) too; else another IK solution,
        from other seeds, that is. Returns the goal and ``then``'s waypoints; ActionFailed
        naming what every solution touches."""
        planner = self._planner()
        follow = then or (lambda _q: [])
        if planner is None:
            return q, follow(q)
        scene = planner.scene()
        planner.sync(scene, self.grasping(), (q_now,), movables=False)
        step = planner.options.validate_step
        rng = entity_rng(self.world.seed, f"ik-goal:{self.name}:{planner.plans}")
        touched: dict[str, int] = {}
        tries = 0
        candidate: np.ndarray | None = q
        for attempt in range(IK_GOAL_TRIES + 1):
            if attempt:
                seed = rng.uniform(np.maximum(scene.lower, -np.pi),
                                   np.minimum(scene.upper, np.pi))
                try:
                    candidate = cartesian.solve(self.services(), tip, pose, seed, free)
                except cartesian.CartesianError:
                    continue
            assert candidate is not None
            tries += 1
            try:
                line = follow(candidate)
            except cartesian.CartesianError:
                continue
            blocked = scene.first_blocked([candidate, *line], step)
            if blocked is None:
                return candidate, line
            for a, b in scene.contacts(blocked):
                touched[f"{a} touches {b}"] = touched.get(f"{a} touches {b}", 0) + 1
        named = "; ".join(f"{k} ({v} of {tries})" for k, v in
                          sorted(touched.items(), key=lambda kv: -kv[1])[:4])
        what = "or its approach " if then is not None else ""
        raise ActionFailed(f"every IK solution found for the pose ({tries}) {what}is in "
                           f"collision: {named or 'no solution'}")

    def _start_planning(self, robot: Robot, q_now: np.ndarray) -> None:
        """Check the plannable stage's direct move; start a plan when it is needed."""
        self._planning = None
        index = next((i for i, st in enumerate(self.stages) if st.plannable), None)
        if not self.PLANS or index is None:
            return
        mode = self.get_input("planner")
        start = q_now if index == 0 else self.stages[index - 1].command
        goal = self.stages[index].command
        self.set_output("path_length", float(np.linalg.norm(goal - start)))
        self.set_output("plan_samples", 0)
        planner = self._planner()
        if planner is None:
            return
        scene = planner.scene()
        if not self.stages[index].goal_checked:  # a goal must be free without padding
            planner.sync(scene, self.grasping(), (start,), movables=False)
            try:
                check_end(scene, goal, "goal")
            except PlanError as exc:
                raise ActionFailed(f"planning the arm's move: {exc}") from None
        padding = self.get_input("padding", None)
        if padding is None:
            padding = self.robot().description.planning.padding
        planner.sync(scene, self.grasping(), (start, goal), float(padding))
        if mode == "auto" and planner.direct_is_free(scene, start, goal):
            return
        self._planning = (index, planner.steps(scene, start, goal, self.name))
        robot.hold_arm()

    def _advance_planning(self) -> bool:
        """One tick of planning; True when the plan is ready (its stages spliced in)."""
        assert self._planning is not None
        index, steps = self._planning
        planner = self._planner()
        assert planner is not None
        spent = 0
        began = time.perf_counter()
        try:
            while spent < CHECKS_PER_TICK:
                spent = next(steps)
        except StopIteration as done:
            result = done.value
        except PlanError as exc:
            raise ActionFailed(f"planning the arm's move: {exc}") from None
        else:
            return False
        finally:
            planner.wall_time += time.perf_counter() - began
        planner.samples += int(result.samples)
        self._draw(planner, result.path)
        arm = self.robot().description.arm
        stage = self.stages[index]
        stage.trajectory = time_parameterise(
            result.path, [v * self.speed for v in arm.velocity_limits],
            [a * self.speed for a in arm.acceleration_limits])
        stage.joints = list(range(len(stage.command)))
        self.set_output("path_length", path_length(result.path))
        self.set_output("plan_samples", int(result.samples))
        self._planning = None
        return True

    def _draw(self, planner: ArmPlanner, path: list[np.ndarray]) -> None:
        """Draw the grasp frame's way along the planned ``path`` (drawn when a viewer or a
        recording is on)."""
        self.overlay.show_path("arm_plan", planner.tool_path(path), rgba=ARM_PATH_COLOUR)

    def start(self) -> None:
        robot = self.robot()
        self.units = self.get_input("units")
        self.tol = float(self.get_input("tolerance"))
        speed = float(self.get_input("speed"))
        if not 0.0 < speed <= 1.0:
            raise ActionFailed(f"speed must be in (0, 1], got {speed}")
        self.speed = speed
        self.timeout = float(self.get_input("joint_timeout"))
        self.check = bool(self.get_input("check_collisions"))
        self.via_tol = (
            float(self.get_input("via_tolerance")) if "via_tolerance" in self.INPUT_PORTS
            else VIA_TOLERANCE
        )
        arm = robot.description.arm
        q_now = robot.arm_positions()
        stages = [st for st in self.plan(q_now) if st.joints]
        lower = [float(v) for v in arm.lower]
        upper = [float(v) for v in arm.upper]
        for st in stages:
            command = st.command.tolist()
            for j in st.joints:
                if not lower[j] - 1e-9 <= command[j] <= upper[j] + 1e-9:
                    raise ActionFailed(
                        f"joint {j} ({arm.joints[j]}) target {_fmt(command[j], self.units)} is "
                        f"outside its limits [{_fmt(lower[j], self.units)}, "
                        f"{_fmt(upper[j], self.units)}]"
                    )
        self.stages = stages
        self.command = q_now.copy()
        self._command = q_now.tolist()
        self.stage = -1
        self._follow: tuple[Trajectory, float] | None = None
        self._last_tick = -1.0
        # each joint's allowed speed, and the least it may correct at, fixed for the move
        vmax = np.asarray(arm.velocity_limits, dtype=float) * self.speed
        self._vmax: list[float] = vmax.tolist()
        self._floor: list[float] = (CORRECTION_SPEED * vmax).tolist()
        # contacts the arm already has may stay (it can then move away from them); only new
        # ones end the move
        self.initial_contacts = set(arm_collisions(self.world, robot)) if self.check else set()
        if self.LINE_CHECK and self.check:
            self._check_lines(q_now, stages)
        self._start_planning(robot, q_now)
        if self._planning is None:
            self._next_stage(robot, robot.arm_motion()[0])

    def _next_stage(self, robot: Robot, q: list[float]) -> None:
        """Start the next stage from the arm's joint positions ``q`` (rad)."""
        self.stage += 1
        self.stage_started = self.now()
        if self.stage >= len(self.stages):
            return
        stage = self.stages[self.stage]
        target = stage.command
        self.command = target.copy()
        self._command = target.tolist()
        if stage.trajectory is not None and stage.trajectory.duration > 0.0:
            self._follow = (stage.trajectory, self.now())
            self._track(robot)
            return
        if self.SWEEPS and self.check:
            self._check_sweep(np.asarray(q, dtype=float), stage)
        self._settle_on(robot, q)

    def _check_sweep(self, q: np.ndarray, stage: Stage) -> None:
        """ActionFailed naming what the arm (or what it carries) would touch of the walls,
        furniture and floor on its way from ``q`` to the stage's command, checked in the
        planning scene before it moves (what it touches at ``q`` already may stay)."""
        hits = self._world_hits(q, [stage.command])
        if hits:
            robot = self.robot()
            joints = robot.description.arm.joints
            moving = ", ".join(f"{j} ({joints[j]})" for j in stage.joints)
            robot.hold_arm()
            raise ActionFailed(f"joint {moving} would collide on its way: {hits}")

    def _check_lines(self, q_now: np.ndarray, stages: list[Stage]) -> None:
        """ActionFailed naming what the arm (or what it carries) would touch of the walls,
        furniture and floor along the straight moves of ``stages`` (the runs of stages that
        are not planned: a planned stage's way is the planner's), before the arm moves."""
        runs: list[list[np.ndarray]] = [[q_now]]
        for st in stages:
            if st.plannable:
                runs.append([st.command])
            else:
                runs[-1].append(st.command)
        for run in runs:
            if len(run) > 1:
                hits = self._world_hits(run[0], run[1:])
                if hits:
                    raise ActionFailed(f"{self.LINE_NAME} would collide: {hits}")

    def _world_hits(self, q: np.ndarray, waypoints: list[np.ndarray]) -> str:
        """What of the walls, furniture and floor the arm (or what it carries) would touch on
        the straight joint moves from ``q`` through ``waypoints`` ("" for nothing), checked in
        the planning scene at the planner's validation step. The arm against itself is not
        checked (nor is it while it moves), nor are movable objects (it may push them); what it
        touches at ``q`` already may stay."""
        planner = self.arm_planner()
        scene = planner.scene()
        planner.sync(scene, "", (q,), movables=False)
        step = planner.options.validate_step
        here_from = q
        for there in waypoints:
            n = max(1, math.ceil(float(np.max(np.abs(there - here_from))) / step))
            for k in range(1, n + 1):
                here = here_from + (there - here_from) * (k / n)
                if scene.collides(here):
                    hits = [p for p in scene.contacts(here)
                            if p[0] in scene.obstacles or p[1] in scene.obstacles]
                    if hits:
                        return named_contacts(hits)
            here_from = there
        return ""

    def _settle_on(self, robot: Robot, q: list[float]) -> None:
        """Send the stage's command from the joint positions ``q`` (rad)."""
        joints = self.stages[self.stage].joints
        # joints moved together arrive together: scale each speed to the slowest travel time
        command, vmax = self._command, self._vmax
        travel = [abs(command[j] - q[j]) for j in joints]
        t = _largest([d / vmax[j] for d, j in zip(travel, joints, strict=True)]) if joints else 0.0
        self._send(robot, joints, travel, t)

    def _track(self, robot: Robot) -> bool:
        """Follow the stage's trajectory: give the arm its position a tick ahead, at no more
        than the speed it has there (plus the correction margin). False once it has run out
        (the stage's command is then sent, and the stage's time-out starts)."""
        assert self._follow is not None
        trajectory, t0 = self._follow
        now = self.now()
        ahead = max(now - self._last_tick, MIN_LOOKAHEAD) if self._last_tick >= 0 else (
            DEFAULT_LOOKAHEAD)
        self._last_tick = now
        t = now - t0
        if t >= trajectory.duration:
            self._follow = None
            self.stage_started = now
            self._settle_on(robot, robot.arm_motion()[0])
            return False
        target = trajectory.position(t + ahead)
        speed = np.maximum(np.abs(trajectory.velocity(t)), np.abs(trajectory.velocity(t + ahead)))
        caps = np.maximum(speed * TRACK_MARGIN, self._floor)
        robot.set_arm_targets(target, max_velocity=caps.tolist())
        return True

    def _send(self, robot: Robot, joints: list[int], travel: list[float], t: float) -> None:
        """Command the stage. The moving joints get speeds that make them arrive together;
        every joint may correct at no less than :data:`CORRECTION_SPEED` of its allowed speed, so
        a joint that a load pushes away can come back."""
        speeds = list(self._floor)
        if t > 1e-9:
            for d, j in zip(travel, joints, strict=True):
                # numpy.maximum(d / t, floor) on plain floats (a NaN wins, as there)
                v, f = d / t, speeds[j]
                speeds[j] = f if f > v or f != f else v
        else:
            for j in joints:
                speeds[j] = self._vmax[j]
        robot.set_arm_targets(self.command, max_velocity=speeds)

    def step(self) -> Status:
        robot = self.robot()
        if self._planning is not None:
            if not self._advance_planning():
                return Status.RUNNING
            self.stage_started = self.now()
            self._next_stage(robot, robot.arm_motion()[0])
            return Status.RUNNING
        if self.check:
            hits = sorted(set(arm_collisions(self.world, robot)) - self.initial_contacts)
            if hits:
                robot.hold_arm()
                raise ActionFailed(self._where() + ": " + "; ".join(hits))
        if self.stage >= len(self.stages):
            return Status.SUCCESS
        if self._follow is not None and self._track(robot):
            return Status.RUNNING
        # every joint, not only the moving ones, must be where it was told to be: a load can
        # push a holding joint away, and the move is not done until it is back
        q, qd = robot.arm_motion()
        err = list(map(abs, map(operator.sub, q, self._command)))
        # "every e < tol" as tol > e on each (False for a NaN, as numpy's comparison)
        if self.stages[self.stage].via:
            arrived = all(map(float(self.via_tol).__gt__, err))
        else:
            arrived = all(map(float(self.tol).__gt__, err)) and all(
                map(SETTLE_SPEED.__gt__, map(abs, qd))
            )
        if arrived:
            self._next_stage(robot, q)
            if self.stage >= len(self.stages):
                return Status.SUCCESS
            return Status.RUNNING
        if self.now() - self.stage_started > self.timeout:
            worst = int(np.argmax(err))
            robot.hold_arm()
            raise ActionFailed(
                f"{self._where()}: joint {worst} stopped at {_fmt(q[worst], self.units)}, "
                f"{_fmt(err[worst], self.units)} from its target after {self.timeout:g} s"
            )
        return Status.RUNNING

    def _where(self) -> str:
        joints = self.stages[self.stage].joints if 0 <= self.stage < len(self.stages) else []
        return f"moving joint {joints[0]}" if len(joints) == 1 else "moving the arm"


@registry.register
class MoveJointsSequentially(JointMove):
    """Moves arm joints to their targets ONE AT A TIME, in the given order.

    - RUNNING while a joint moves (the others hold their positions);
    - SUCCESS when every joint named in ``order`` has reached its target within ``tolerance``;
    - FAILURE when a target is outside its joint limits, a joint does not arrive within
      ``joint_timeout`` s, or the arm (or what it carries) comes into contact with a wall,
      furniture or the floor (contacts it already had when it started do not count); with
      ``check_collisions``, each joint's sweep is checked in the arm's planning scene before
      the joint moves, and one that would meet a wall, furniture or the floor ends the node
      with FAILURE naming what would touch, the arm unmoved.
    Halted: the arm holds where it is.
    """

    SWEEPS = True

    INPUT_PORTS: dict[str, PortInformation] = {
        **JointMove.INPUT_PORTS,
        "targets": PortInformation(
            list[float], True, "joint targets, one per arm joint (deg or rad, see units)"
        ),
        "order": Port(
            list[int], False, "joint indices in the order to move them (empty: 0, 1, ...)", [],
            NON_NEGATIVE,
        ),
    }

    def plan(self, q_now: np.ndarray) -> list[Stage]:
        targets = to_radians(self.get_input("targets"), self.get_input("units"))
        n = len(q_now)
        if len(targets) != n:
            raise ActionFailed(f"targets has {len(targets)} values; the arm has {n} joints")
        order = list(self.get_input("order")) or list(range(n))
        bad = [j for j in order if not 0 <= j < n]
        if bad or len(set(order)) != len(order):
            raise ActionFailed(f"order must list distinct joint indices 0..{n - 1}, got {order}")
        stages = []
        command = q_now.copy()
        for j in order:
            command = command.copy()
            command[j] = targets[j]
            stages.append(Stage(command, [j]))
        return stages


@registry.register
class MoveJoints(JointMove):
    """Moves all arm joints together to ``targets`` or to a named arm ``state`` (e.g. tuck).

    With ``planner="auto"`` the move is first checked in the arm's planning scene (the world's
    bodies near the arm, what it holds) and, when the direct joint move would hit something,
    planned round it (RRT-Connect; ``rrtconnect`` always plans); ``path_length`` and
    ``plan_samples`` say what was moved and drawn (robots/README.md, docs/motion-planning.md).

    - RUNNING while the arm moves (joints are timed to arrive together), and while a plan is
      searched (at most 4000 collision checks per tick, the arm holding still);
    - SUCCESS when every joint is within ``tolerance`` of its target;
    - FAILURE on an unknown state, targets outside the limits, a time-out, or a collision; with a
      planner also when the goal is in collision (naming what touches) or no path is found
      within the budget (saying how far the search grew).
    Halted: the arm holds where it is.
    """

    REQUIRED_ONE_OF = (("targets", "state"),)
    PLANS = True
    INPUT_PORTS: dict[str, PortInformation] = {
        **JointMove.INPUT_PORTS,
        "targets": PortInformation(
            list[float], False, "joint targets (deg or rad, see units), or use state", []
        ),
        "state": PortInformation(str, False, "named arm state of the robot descriptor", ""),
        "planner": PLANNER,
        "padding": PADDING_PORT,
    }
    OUTPUT_PORTS: dict[str, PortInformation] = dict(PLAN_OUTPUTS)

    def plan(self, q_now: np.ndarray) -> list[Stage]:
        state = self.get_input("state")
        values = self.get_input("targets")
        if bool(state) == bool(values):
            raise ActionFailed('give exactly one of targets="..." or state="..."')
        if state:
            states = self.robot().description.states
            if state not in states:
                raise ActionFailed(f"unknown arm state '{state}'; known: {', '.join(states)}")
            targets = np.asarray(states[state], dtype=float)
        else:
            targets = to_radians(values, self.get_input("units"))
        if len(targets) != len(q_now):
            raise ActionFailed(f"targets has {len(targets)} values; the arm has {len(q_now)}")
        return [Stage(targets, list(range(len(q_now))), plannable=True)]


@registry.register
class Lift(JointMove):
    """Lifts what the gripper holds: by joint ``deltas`` (one joint at a time), or straight up
    by ``height`` metres (a vertical line of IK waypoints, orientation kept).

    The straight lift passes its waypoints within ``via_tolerance`` per joint: 0.01 rad keeps
    the tool within about a millimetre of the vertical, to slide a board out of a slot that
    leaves it 3 mm on each side.

    Scenario A's lift is ``deltas="0;-50;-30;0;0;0"`` (deg): joint 1 up by 50 deg, then joint 2
    by 30 deg. ``order`` picks the sequence (default: joints with a non-zero delta, in index
    order).

    - RUNNING while moving; SUCCESS when the arm is at the last target within ``tolerance``;
    - FAILURE when a target is outside the limits or unreachable, on a time-out, or on a
      collision; before the arm moves, when the lift would bring the arm or what it carries
      against a wall, furniture or the floor (checked in the arm's planning scene), naming what.
    Halted: the arm holds where it is.
    """

    LINE_CHECK = True
    LINE_NAME = "the lift"

    REQUIRED_ONE_OF = (("deltas", "height"),)
    INPUT_PORTS: dict[str, PortInformation] = {
        **JointMove.INPUT_PORTS,
        "deltas": PortInformation(
            list[float], False, "change of each arm joint (deg or rad, see units)", []
        ),
        "order": Port(list[int], False, "joints in the order to move them", [], NON_NEGATIVE),
        "height": PortInformation(float, False, "lift straight up by this much (m)", 0.0),
        "via_tolerance": VIA,
    }

    def plan(self, q_now: np.ndarray) -> list[Stage]:
        values = self.get_input("deltas")
        height = float(self.get_input("height"))
        if bool(values) == (height != 0.0):
            raise ActionFailed('give exactly one of deltas="..." or height="..."')
        n = len(q_now)
        if height:
            robot = self.robot()
            tip = robot.description.grasp_frame
            start = robot.link_transform(tip)
            goal = start.copy()
            goal[2, 3] += height
            path = cartesian.line(self.services(), tip, start, goal, q_now)
            return _through(path, n)
        deltas = to_radians(values, self.get_input("units"))
        if len(deltas) != n:
            raise ActionFailed(f"deltas has {len(deltas)} values; the arm has {n} joints")
        order = list(self.get_input("order")) or [j for j in range(n) if deltas[j] != 0.0]
        if any(not 0 <= j < n for j in order):
            raise ActionFailed(f"order must list joint indices 0..{n - 1}, got {order}")
        stages = []
        command = q_now.copy()
        for j in order:
            command = command.copy()
            command[j] = q_now[j] + deltas[j]
            stages.append(Stage(command, [j]))
        return stages


@registry.register
class MoveToPose(JointMove):
    """Moves the gripper (or ``frame``) to a pose in the world, found by inverse kinematics.

    The target position is ``position`` (x;y;z) or the centre of ``object``, plus ``offset`` (x;y;z,
    world frame); an object's pose is the one the robot perceives (ground truth plus any ``--inject
    pose_noise``). With ``grasp="top"`` the target is the object's top grasp frame instead
    (:mod:`bt_manip.manipulation.grasps`: from above, at the middle of its top face, the fingers
    closing across its thinner side; ``orientation`` and ``match_object_yaw`` are then not used).
    The orientation is ``orientation`` (quaternion x;y;z;w, world frame; default ``0;1;0;0``: the
    tool pointing straight down). The frame placed is the robot's grasp frame, whose z axis is
    the gripper's approach direction (the descriptor's ``approach_axis``, see robots/README.md).
    With ``match_object_yaw`` the orientation is turned about the
    vertical to the object's yaw (modulo 90 deg, the turn nearest the current wrist), so a parallel
    gripper closes on two faces of a box; with ``free_yaw`` the rotation about the tool axis is left
    to the solver. ``path="line"`` moves the tool on a straight line from where it is (orientation
    turning evenly); the default ``joint`` interpolates the joints. With ``approach`` > 0 the last
    ``approach`` metres are a straight line along the tool axis; with ``retreat`` > 0 the move
    starts by backing out that far along the tool axis from where the tool is (leaving a grasp or a
    drop the way it came).

    With ``planner="auto"`` (``path="joint"`` only) the IK solution must be free in the arm's
    planning scene, with its approach: other IK seeds and the tool's other quarter turns about
    the object are tried; then the joint move is planned round what it would hit, as for
    MoveJoints.

    - RUNNING while the arm moves through the joint waypoints, and while a plan is searched;
    - SUCCESS when the last waypoint is reached within ``tolerance``;
    - FAILURE when no configuration reaches the pose (the reason says why: beyond reach, joint
      limits, not converged), on a time-out, or on a collision with walls, furniture or floor;
      with a planner also when every IK solution (or its approach) is in collision, naming what
      each touches, or when no path is found within the budget; before the arm moves, when a
      straight part of the move (the retreat, a ``path="line"`` move, the approach) would bring
      the arm or what it carries against a wall, furniture or the floor, naming what.
    Halted: the arm holds where it is.
    """

    LINE_CHECK = True

    REQUIRED_ONE_OF = (("position", "object"),)
    INPUT_PORTS: dict[str, PortInformation] = {
        **JointMove.INPUT_PORTS,
        "position": Port(list[float], False, "target x;y;z (m, world)", [], count_of(0, 3)),
        "object": PortInformation(str, False, "target the centre of this object", ""),
        "grasp": Port(
            str, False, "target this grasp of object instead of its centre: top (see grasps)", "",
            Accepts(choices=("", "top")),
        ),
        "offset": Port(
            list[float], False, "added to the target x;y;z (m, world)", [0.0, 0.0, 0.0], count_of(3)
        ),
        "orientation": Port(
            list[float], False, "quaternion x;y;z;w (world)", [0.0, 1.0, 0.0, 0.0], count_of(4)
        ),
        "match_object_yaw": PortInformation(bool, False, "turn with the object's yaw", False),
        "free_yaw": PortInformation(
            bool, False, "leave the rotation about the tool axis free", False
        ),
        "approach": Port(
            float, False, "straight-line approach length (m)", 0.0, NON_NEGATIVE
        ),
        "retreat": Port(
            float, False, "first back out this far along the tool axis (m)", 0.0, NON_NEGATIVE
        ),
        "frame": PortInformation(str, False, "robot link to place (default: grasp frame)", ""),
        "path": Port(
            str, False, "joint: interpolate joints; line: straight line from where it is", "joint",
            Accepts(choices=("joint", "line")),
        ),
        "via_tolerance": VIA,
        "planner": PLANNER,
        "padding": PADDING_PORT,
    }
    OUTPUT_PORTS: dict[str, PortInformation] = dict(PLAN_OUTPUTS)
    PLANS = True

    def grasping(self) -> str:
        return str(self.get_input("object") or "")

    def plan(self, q_now: np.ndarray) -> list[Stage]:
        robot = self.robot()
        tip = self.get_input("frame") or robot.description.grasp_frame
        position = list(self.get_input("position"))
        name = self.get_input("object")
        if bool(position) == bool(name):
            raise ActionFailed('give exactly one of position="x;y;z" or object="name"')
        grasp = self.get_input("grasp")
        if grasp and not name:
            raise ActionFailed(f'grasp="{grasp}" needs object="name"')
        yaw = None
        if name:
            seen = self.perceived_pose(name)  # what the robot sees: ground truth + pose noise
            position = list(seen[:3, 3])
            yaw = math.atan2(seen[1, 0], seen[0, 0])
        offset = self.get_input("offset")
        if len(position) != 3 or len(offset) != 3:
            raise ActionFailed("position and offset take three numbers x;y;z")
        if grasp:
            target = object_grasp(
                self.world, self.faults(), robot, name, grasp, robot.base_pose2d()[2]
            )
            target[:3, 3] += np.asarray(offset, dtype=float)
        else:
            target = pose_matrix(np.add(position, offset), self.get_input("orientation"))
        turns = [target]
        if self.get_input("match_object_yaw") and yaw is not None and not grasp:
            turns = self._turns(robot, tip, target, yaw)
            target = turns[0]
        self.overlay.show_frame("ik_target", target)  # drawn when a viewer is on
        services = self.services()
        free = bool(self.get_input("free_yaw"))
        approach = float(self.get_input("approach"))
        retreat = float(self.get_input("retreat"))
        if approach < 0 or retreat < 0:
            raise ActionFailed("approach and retreat are distances: they cannot be negative")
        try:
            if self._planner() is None or self.get_input("path") != "joint":
                return self._stages(robot, tip, target, q_now, services, free, approach, retreat)
            # planning: a turn of the tool by another quarter turn may clear what the first hits
            for k, turned in enumerate(turns):
                try:
                    return self._stages(robot, tip, turned, q_now, services, free, approach,
                                        retreat)
                except ActionFailed:
                    if k == len(turns) - 1:
                        raise
            raise AssertionError("unreachable")
        except cartesian.CartesianError as exc:
            raise cartesian.CartesianError(_with_knobs(str(exc), free, approach,
                                                       self.get_input("path"))) from None

    def _stages(self, robot: Robot, tip: str, target: np.ndarray, q_now: np.ndarray,
                services: RobotServices, free: bool, approach: float, retreat: float
                ) -> list[Stage]:
        """The joint waypoints to ``target``: back out, go there, approach."""
        n = len(q_now)
        here = robot.link_transform(tip)
        stages: list[Stage] = []
        if retreat > 0:
            # leave along the tool axis first, as the tool came in
            back = here.copy()
            back[:3, 3] -= retreat * here[:3, 2]
            path = cartesian.line(services, tip, here, back, q_now)
            stages += [Stage(q, list(range(n)), via=True) for q in path]
            here, q_now = back, path[-1]
        first = target.copy()
        if approach > 0:
            first[:3, 3] -= approach * target[:3, 2]
        if self.get_input("path") == "line":
            stages += _through(cartesian.line(services, tip, here, first, q_now, free), n)
            q_first = stages[-1].command
        elif self.get_input("path") == "joint":
            q_first = cartesian.solve(services, tip, first, q_now, free)

            def approach_line(q: np.ndarray) -> list[np.ndarray]:
                if approach <= 0:
                    return []
                return list(cartesian.line(services, tip, first, target, q, free))

            q_first, line = self._free_goal(tip, first, q_first, q_now, free, approach_line)
            stages.append(Stage(q_first, list(range(n)), plannable=True,
                                goal_checked=self._planner() is not None))
            if approach > 0:
                stages += _through(line, n)
            return stages
        else:
            raise ActionFailed(f"path must be 'joint' or 'line', got '{self.get_input('path')}'")
        if approach > 0:
            stages += _through(cartesian.line(services, tip, first, target, q_first, free), n)
        return stages

    @staticmethod
    def _turns(robot: Robot, tip: str, target: np.ndarray, yaw: float) -> list[np.ndarray]:
        """``target`` turned about the world vertical by the object's yaw plus k x 90 deg, for
        k = 0 .. 3, the turn the tool makes least from where it points now first."""
        now = robot.link_transform(tip)[:3, :3]
        found = []
        for k in range(4):
            a = yaw + k * np.pi / 2
            rz = np.array([[np.cos(a), -np.sin(a), 0], [np.sin(a), np.cos(a), 0], [0, 0, 1]])
            cand = target.copy()
            cand[:3, :3] = rz @ target[:3, :3]
            turn = np.arccos(np.clip((np.trace(now.T @ cand[:3, :3]) - 1) / 2, -1, 1))
            found.append((float(turn), k, cand))
        return [cand for _, _, cand in sorted(found, key=lambda f: (f[0], f[1]))]


def _with_knobs(reason: str, free_yaw: bool, approach: float, path: str) -> str:
    """An IK failure's ``reason`` with the ports of MoveToPose that may get round it in place
    of the solver's options (which a tree does not set)."""
    if not (NOT_CONVERGED in reason or JOINT_LIMITS in reason or BEYOND_REACH in reason):
        return reason
    knobs = []
    if BEYOND_REACH not in reason and not free_yaw:
        knobs.append('free_yaw="true" (the rotation about the tool axis left to the solver)')
    knobs.append("another orientation or offset")
    if path == "line":
        knobs.append('path="joint" (no straight line from where the tool is)')
    if approach > 0:
        knobs.append("a shorter approach")
    knobs.append("the base moved (Navigate, PlanBaseForGrasp)")
    text = "try " + ", ".join(knobs)
    if SOLVER_KNOBS in reason:
        return reason.replace(SOLVER_KNOBS, text)
    return f"{reason}; {text}"


def _through(path: list[np.ndarray], n: int) -> list[Stage]:
    """Stages along a waypoint path: pass through every waypoint, stop at the last."""
    joints = list(range(n))
    return [Stage(q, joints, via=i < len(path) - 1) for i, q in enumerate(path)]


def _largest(values: list[float]) -> float:
    """``numpy.max`` of a non-empty list of floats (NaN when one is NaN, as there)."""
    top = values[0]
    for v in values:
        if v > top or v != v:
            top = v
            if v != v:
                break
    return top
