"""Nav2's action nodes, backed by bt-manip's navigation of the robot's base.

- ComputePathToPose: A* on the robot's costmap (:class:`~bt_manip.navigation.navigator.
  Navigator`), written to the blackboard as a :class:`~bt_manip.nav2.path.Nav2Path`.
- FollowPath: the base's path follower on that path; a new path on the blackboard is taken
  over on the fly, as Nav2's controller server does when the tree replans.
- Spin, BackUp, Wait: Nav2's behaviours on the base, with their result codes.

Every node writes Nav2's numeric result code to ``error_code_id`` and its text to
``error_msg`` (0 and "" on success), and fails with the reason in its feedback message.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any, ClassVar, NoReturn

import pybullet as pb
from py_trees.common import Status
from py_trees.ports import PortInformation

from bt_manip.behaviours.base import ActionFailed, RobotAction, skid_steer_refusal
from bt_manip.behaviours.navigate import sync_navigator, synced_navigator
from bt_manip.bt.node import PortError
from bt_manip.bt.ports import NON_NEGATIVE, POSITIVE, Port
from bt_manip.bt.registry import registry
from bt_manip.nav2.blocking import drop_if_due, maybe_block
from bt_manip.nav2.collision_ahead import AheadWatch, blocked_ahead
from bt_manip.nav2.errors import BehaviorError, ControllerError, PlannerError
from bt_manip.nav2.path import Nav2Path, Pose2D, goal_pose, path_from_points
from bt_manip.nav2.tracking import TrackingFeedback, tracking_feedback
from bt_manip.navigation.controller import FollowState, PathFollower
from bt_manip.navigation.planner import PlanOutcome

XY_GOAL_TOLERANCE = 0.25
"""Nav2's default goal checker: distance (m) to the path's last pose that counts as there."""
YAW_GOAL_TOLERANCE = 0.25
"""Nav2's default goal checker: heading error (rad) that counts as there."""

PLAN_ERRORS = {
    PlanOutcome.START_OUTSIDE: PlannerError.START_OUTSIDE_MAP,
    PlanOutcome.GOAL_OUTSIDE: PlannerError.GOAL_OUTSIDE_MAP,
    PlanOutcome.START_BLOCKED: PlannerError.START_OCCUPIED,
    PlanOutcome.GOAL_IN_OBSTACLE: PlannerError.GOAL_OCCUPIED,
    PlanOutcome.FOOTPRINT: PlannerError.NO_VALID_PATH,
    PlanOutcome.NO_PATH: PlannerError.NO_VALID_PATH,
}


def plan_error(outcome: PlanOutcome, reason: str) -> PlannerError:
    """Nav2's planner result code for a failed plan: a start or goal too close to obstacles
    for the footprint is occupied, as in Nav2's costmap."""
    if outcome is PlanOutcome.FOOTPRINT:
        if reason.startswith("goal"):
            return PlannerError.GOAL_OCCUPIED
        if reason.startswith("start"):
            return PlannerError.START_OCCUPIED
    return PLAN_ERRORS.get(outcome, PlannerError.UNKNOWN)


def error_ports(doc: str) -> dict[str, PortInformation]:
    """Nav2's ``error_code_id`` and ``error_msg`` output ports."""
    return {
        "error_code_id": PortInformation(int, False, f"{doc} error code"),
        "error_msg": PortInformation(str, False, f"{doc} error message"),
    }


class Nav2Failed(ActionFailed):
    """A failure with Nav2's result code."""

    def __init__(self, code: int, reason: str) -> None:
        super().__init__(reason)
        self.code = int(code)


class Nav2Action(RobotAction):
    """A Nav2 action: reports Nav2's result code and message on its ports (0 and "" while it
    runs and on SUCCESS; on FAILURE the code given to :meth:`fail`, else ``UNKNOWN``). As
    Nav2's action nodes, it starts again when ticked after it finished (it is not stateful).

    Subclasses implement :meth:`begin` (instead of ``start``) and ``step``.
    """

    STATEFUL = False
    UNKNOWN: ClassVar[int] = 0
    """The result code of a failure that gave none (Nav2's UNKNOWN of the server)."""
    _code: int = 0

    def initialise(self) -> None:
        self._set_result(0, "")
        super().initialise()
        if self._start_error is not None:
            self._set_result(self._code, self._start_error)

    def update(self) -> Status:
        self._code = int(self.UNKNOWN)
        status = super().update()
        if status == Status.FAILURE and self._start_error is None:
            self._set_result(self._code, self.feedback_message)
        elif status == Status.SUCCESS:
            self._set_result(0, "")
        return status

    def fail(self, code: int, reason: str) -> NoReturn:
        """End the action with FAILURE, result ``code`` and ``reason``."""
        self._code = int(code)
        raise Nav2Failed(code, reason)

    def _set_result(self, code: int, message: str) -> None:
        self.set_output("error_code_id", int(code))
        self.set_output("error_msg", message)

    def base(self) -> Any:
        robot = self.robot()
        refusal = skid_steer_refusal(robot, self.NODE_ID)
        if refusal is not None:
            self.fail(self.UNKNOWN, refusal)
        return robot

    def start(self) -> None:
        self._code = int(self.UNKNOWN)
        try:
            self.begin()
        except Nav2Failed as exc:
            self._code = exc.code
            raise

    def begin(self) -> None:
        """Prepare the action; call :meth:`fail` to fail at once."""


def contacts(world: Any, robot: Any, robot_name: str) -> set[str]:
    """Bodies other than the floor that the robot or what it holds touch now."""
    ground = world.body_id("ground")
    mine = {robot.body} | {a.object_body for a in world.attachments.held_by(robot_name)}
    out = set()
    for body in mine:
        for pt in pb.getContactPoints(bodyA=body, physicsClientId=world.client):
            if pt[2] != ground and pt[2] not in mine:
                out.add(world.name_of(pt[2]) or str(pt[2]))
    return out


PLAN_PORTS: dict[str, PortInformation] = {
        "start": PortInformation(object, False, "Start pose of the path (default: the robot)"),
        "planner_id": PortInformation(str, False, "Mapped name to the planner plugin", ""),
}
"""The input ports every Nav2 planning action has (besides its goal or goals)."""


def ahead_of(pose: Pose2D, distance: float) -> tuple[float, float]:
    """The point ``distance`` ahead of ``pose`` along its heading (where the pivot is)."""
    return (pose[0] + distance * math.cos(pose[2]), pose[1] + distance * math.sin(pose[2]))


class PlanAction(Nav2Action):
    """A Nav2 planning action: plans within the tick from the robot (or ``start``), SUCCESS
    once the path is written."""

    def start_pose(self, robot: Any) -> Pose2D:
        """The pose ``start`` names, else the robot's base pose."""
        start_value = self.get_input("start", None)
        return goal_pose(self.world, start_value) if start_value else self.believed_pose(robot)

    def step(self) -> Status:
        return Status.SUCCESS


@registry.register
class ComputePathToPose(PlanAction):
    """Plans a path from the robot (or ``start``) to ``goal`` on the robot's costmap (A*).

    Planning is done within the tick:

    - SUCCESS: ``path`` holds the new :class:`Nav2Path`, ``error_code_id`` 0;
    - FAILURE: no path (goal or start in an obstacle or off the map, no way wide enough):
      ``error_code_id`` is Nav2's code (204 GOAL_OUTSIDE_MAP, 206 GOAL_OCCUPIED,
      208 NO_VALID_PATH, ...) and ``error_msg`` says why; ``path`` is left as it was.

    A ``block`` fault (``--inject block:P``) is drawn for the first route planned to a goal:
    its crate falls when FollowPath brings the robot near its place on the route.
    """

    UNKNOWN = PlannerError.UNKNOWN
    INPUT_PORTS: dict[str, PortInformation] = {
        **RobotAction.INPUT_PORTS,
        "goal": PortInformation(
            object, True, "Destination to plan to (x;y;yaw in m, rad, or a pose name)"
        ),
        **PLAN_PORTS,
    }
    OUTPUT_PORTS: dict[str, PortInformation] = {
        "path": PortInformation(Nav2Path, False, "Path created by ComputePathToPose node"),
        **error_ports("The compute path to pose"),
    }

    def __init__(self, name: str | None = None, **attributes: Any) -> None:
        super().__init__(name, **attributes)
        self.blocked_goals: set[tuple[float, float, float]] = set()

    def begin(self) -> None:
        robot = self.base()
        world = self.world
        goal = goal_pose(world, self.get_input("goal"))
        start = self.start_pose(robot)
        nav = synced_navigator(self, robot)
        nav.refresh()
        p = nav.pivot
        ahead = ahead_of(start, p)
        end = ahead_of(goal, p)
        plan = nav.plan_to((*ahead, start[2]), (*end, goal[2]))
        if not plan.ok or plan.polyline is None:
            # the reason in the base frame's terms when its start or goal is the trouble
            base = nav.plan_to(start, goal)
            failed = plan if base.ok else base
            code = plan_error(failed.outcome, failed.reason) if not base.ok else (
                PlannerError.NO_VALID_PATH
            )
            self.fail(code, f"no path to {goal[0]:.3f};{goal[1]:.3f}: {failed.reason}")
        assert plan.polyline is not None
        path = path_from_points(plan.polyline, goal, p)
        path = dataclasses.replace(path, planner_id=str(self.get_input("planner_id", "") or ""))
        self.set_output("path", path)
        if goal not in self.blocked_goals:
            self.blocked_goals.add(goal)
            maybe_block(self, plan.polyline, f"{goal[0]:.3f};{goal[1]:.3f};{goal[2]:.3f}")


@registry.register
class FollowPath(Nav2Action):
    """Drives the base along ``path`` with the base's path follower, to its last pose.

    - RUNNING while driving; when a new path appears on the blackboard (the tree replanned) it
      is followed from where the robot is, without stopping;
    - SUCCESS when the base is within Nav2's default goal tolerances (0.25 m, 0.25 rad) of the
      path's last pose;
    - ``tracking_feedback`` is written at each tick it drives (:mod:`bt_manip.nav2.tracking`:
      the signed distance of the base's pivot point from the path, the heading error, the
      path length left);
    - FAILURE with 103 INVALID_PATH (no path or an empty one), 105 FAILED_TO_MAKE_PROGRESS
      (the base stopped getting closer) or 106 NO_VALID_CONTROL: a movable object lies on the
      next 0.8 m of the path (checked at 5 Hz, :mod:`bt_manip.nav2.collision_ahead`),
      or the robot ran into something; it stops there.
    Halted: the base is braked where it is.

    A crate of an injected ``block`` fault falls when the robot comes near its place on the
    route (:mod:`bt_manip.nav2.blocking`); it is looked for on the path in the same tick.
    """

    UNKNOWN = ControllerError.UNKNOWN
    INPUT_PORTS: dict[str, PortInformation] = {
        **RobotAction.INPUT_PORTS,
        "path": PortInformation(Nav2Path, True, "Path to follow"),
        "controller_id": PortInformation(str, False, "Mapped name of the controller plugin", ""),
        "goal_checker_id": PortInformation(str, False, "Mapped name of the goal checker", ""),
        "progress_checker_id": PortInformation(
            str, False, "Mapped name of the progress checker", ""
        ),
        "path_handler_id": PortInformation(str, False, "Mapped name of the path handler", ""),
        "server_name": PortInformation(str, False, "Action server name", "follow_path"),
        "server_timeout": PortInformation(float, False, "Action server timeout (ms)", 20.0),
    }
    OUTPUT_PORTS: dict[str, PortInformation] = {
        "tracking_feedback": PortInformation(
            TrackingFeedback, False, "Tracking feedback of the controller: cross track error, "
            "current path index, remaining path length"
        ),
        **error_ports("The follow path"),
    }

    def _path(self) -> Nav2Path:
        try:
            path = self.get_input("path", None)
        except PortError as exc:
            self.fail(ControllerError.INVALID_PATH, str(exc))
        if not isinstance(path, Nav2Path) or len(path) == 0:
            self.fail(ControllerError.INVALID_PATH, f"no path to follow (got {path!r})")
        return path

    def begin(self) -> None:
        robot = self.base()
        self.nav = synced_navigator(self, robot)
        self.path = self._path()
        options = dataclasses.replace(
            self.nav.options.follower,
            pivot=self.nav.pivot,
            xy_tolerance=XY_GOAL_TOLERANCE,
            yaw_tolerance=YAW_GOAL_TOLERANCE,
        )
        self.follower = PathFollower(self.path.shifted(self.nav.pivot), self.path.goal, options)
        self.touching = contacts(self.world, robot, self.robot_name())
        infos = self.world.infos
        self.leaning_on = frozenset(infos[n].body_id for n in self.touching if n in infos)
        """Bodies touched at the start: not obstacles ahead (the robot is already at them)."""
        self.watch = AheadWatch()

    def step(self) -> Status:
        robot = self.robot()
        path = self._path()
        if path is not self.path:
            self.path = path
            self.follower.follow(path.shifted(self.nav.pivot), path.goal)
        bumped = contacts(self.world, robot, self.robot_name()) - self.touching
        if bumped:
            robot.stop_base()
            self.fail(
                ControllerError.NO_VALID_CONTROL,
                "ran into " + ", ".join(f"'{b}'" for b in sorted(bumped)),
            )
        pose = self.believed_pose(robot)
        pivot = ahead_of(pose, self.nav.pivot)
        dropped = drop_if_due(self, *pivot)
        if self.watch.due(self.now()) or dropped is not None:
            sync_navigator(self.world, self.robot_name(), self.nav)  # objects that appeared
            blocked = blocked_ahead(self.nav, path.shifted(self.nav.pivot), pivot,
                                    self.leaning_on)
            if blocked is not None:
                robot.stop_base()
                self.fail(
                    ControllerError.NO_VALID_CONTROL,
                    f"collision ahead: '{blocked.name}' lies on the path "
                    f"{blocked.distance:.2f} m ahead",
                )
        points = path.shifted(self.nav.pivot)
        self.set_output("tracking_feedback", tracking_feedback(points, path.goal, pivot, pose))
        status = self.follower.update(pose, self.now())
        if status.state is FollowState.SUCCEEDED:
            robot.stop_base()
            return Status.SUCCESS
        if status.state is FollowState.FAILED:
            robot.stop_base()
            self.fail(ControllerError.FAILED_TO_MAKE_PROGRESS, status.reason)
        robot.set_base_twist(*status.cmd)
        return Status.RUNNING


class _BaseBehavior(Nav2Action):
    """Spin, BackUp and DriveOnHeading: a timed motion of the base, stopped by contact."""

    UNKNOWN = BehaviorError.UNKNOWN

    def begin(self) -> None:
        robot = self.base()
        self.origin = self.odom_pose(robot)
        self.allowance = float(self.get_input("time_allowance"))
        self.check = not bool(self.get_input("disable_collision_checks"))
        self.touching = contacts(self.world, robot, self.robot_name())

    def step(self) -> Status:
        robot = self.robot()
        if self.check:
            new = contacts(self.world, robot, self.robot_name()) - self.touching
            if new:
                robot.stop_base()
                self.fail(
                    BehaviorError.COLLISION_AHEAD,
                    "collision: touched " + ", ".join(f"'{n}'" for n in sorted(new)),
                )
        twist = self.motion(self.odom_pose(robot))
        if twist is None:
            robot.stop_base()
            return Status.SUCCESS
        if self.elapsed() > self.allowance:
            robot.stop_base()
            self.fail(BehaviorError.TIMEOUT, f"not done after {self.allowance:g} s")
        robot.set_base_twist(*twist)
        return Status.RUNNING

    def motion(self, pose: tuple[float, float, float]) -> tuple[float, float] | None:
        """The twist to apply now, or None when done."""
        raise NotImplementedError


BEHAVIOR_PORTS: dict[str, PortInformation] = {
    **RobotAction.INPUT_PORTS,
    "time_allowance": Port(float, False, "Allowed time for the behavior (s)", 10.0, POSITIVE),
    "disable_collision_checks": PortInformation(
        bool, False, "Disable collision checking", False
    ),
    "is_recovery": PortInformation(bool, False, "True if the behavior is a recovery", True),
}

MAX_SPIN_RATE = 1.0
MIN_SPIN_RATE = 0.4
SPIN_ACCEL = 3.2


@registry.register
class Spin(_BaseBehavior):
    """Turns the base on the spot by ``spin_dist`` radians (the sign says which way).

    - RUNNING while turning (at most 1 rad/s, slowing down near the end);
    - SUCCESS once the base has turned by ``spin_dist``;
    - FAILURE with 701 TIMEOUT after ``time_allowance`` s, or 703 COLLISION_AHEAD when the
      robot touches something (unless ``disable_collision_checks``).
    Halted: the base is braked where it is.
    """

    INPUT_PORTS: dict[str, PortInformation] = {
        **BEHAVIOR_PORTS,
        "spin_dist": Port(float, False, "Spin distance (rad)", 1.57),
    }
    OUTPUT_PORTS: dict[str, PortInformation] = error_ports("Spin")

    def begin(self) -> None:
        super().begin()
        self.target = float(self.get_input("spin_dist"))
        self.turned = 0.0
        self.last_yaw = self.origin[2]

    def motion(self, pose: tuple[float, float, float]) -> tuple[float, float] | None:
        self.turned += math.remainder(pose[2] - self.last_yaw, math.tau)
        self.last_yaw = pose[2]
        left = abs(self.target) - abs(self.turned) if self.turned * self.target >= 0 else abs(
            self.target
        ) + abs(self.turned)
        if left <= 0.0:
            return None
        rate = min(MAX_SPIN_RATE, max(MIN_SPIN_RATE, math.sqrt(2.0 * SPIN_ACCEL * left)))
        return (0.0, math.copysign(rate, self.target))


class _Drive(_BaseBehavior):
    """Drives straight by ``distance`` at ``speed`` (negative: backwards)."""

    def setup_drive(self, distance: float, speed: float) -> None:
        if distance == 0.0 or speed == 0.0:
            self.fail(BehaviorError.UNKNOWN, "distance and speed must not be zero")
        self.distance = abs(distance)
        self.speed = math.copysign(abs(speed), distance)

    def motion(self, pose: tuple[float, float, float]) -> tuple[float, float] | None:
        if math.hypot(pose[0] - self.origin[0], pose[1] - self.origin[1]) >= self.distance:
            return None
        return (self.speed, 0.0)


@registry.register
class BackUp(_Drive):
    """Drives the base straight backwards by ``backup_dist`` metres at ``backup_speed``.

    - RUNNING while reversing;
    - SUCCESS once the distance has been covered;
    - FAILURE with 701 TIMEOUT after ``time_allowance`` s, or 703 COLLISION_AHEAD when the
      robot touches something (it stops there).
    Halted: the base is braked where it is.
    """

    INPUT_PORTS: dict[str, PortInformation] = {
        **BEHAVIOR_PORTS,
        "backup_dist": Port(float, False, "Distance to backup (m)", 0.15, POSITIVE),
        "backup_speed": Port(float, False, "Speed at which to backup (m/s)", 0.025, POSITIVE),
    }
    OUTPUT_PORTS: dict[str, PortInformation] = error_ports("Back up")

    def begin(self) -> None:
        super().begin()
        self.setup_drive(
            -float(self.get_input("backup_dist")), float(self.get_input("backup_speed"))
        )


@registry.register
class DriveOnHeading(_Drive):
    """Drives the base straight along its heading by ``dist_to_travel`` at ``speed``
    (a negative distance drives backwards); statuses as :class:`BackUp`."""

    INPUT_PORTS: dict[str, PortInformation] = {
        **BEHAVIOR_PORTS,
        "dist_to_travel": Port(float, False, "Distance to travel (m)", 0.15),
        "speed": Port(float, False, "Speed at which to travel (m/s)", 0.025, POSITIVE),
    }
    OUTPUT_PORTS: dict[str, PortInformation] = error_ports("Drive on heading")

    def begin(self) -> None:
        super().begin()
        self.setup_drive(float(self.get_input("dist_to_travel")), float(self.get_input("speed")))


@registry.register
class Wait(Nav2Action):
    """Waits ``wait_duration`` seconds of sim time: RUNNING until then, then SUCCESS."""

    INPUT_PORTS: dict[str, PortInformation] = {
        "wait_duration": Port(float, False, "Wait time (s)", 1.0, NON_NEGATIVE),
    }
    OUTPUT_PORTS: dict[str, PortInformation] = error_ports("Wait")
    UNKNOWN = BehaviorError.UNKNOWN

    def begin(self) -> None:
        self.duration = float(self.get_input("wait_duration"))

    def step(self) -> Status:
        return Status.SUCCESS if self.elapsed() >= self.duration - 1e-9 else Status.RUNNING

    def _make_safe(self) -> None:
        pass
