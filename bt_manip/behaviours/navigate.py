"""Navigate: drive the mobile base to a pose through the world's rooms.

The path is planned on an occupancy grid of the world (A*; over poses while something long is
carried) and followed by the base controller, one twist per tick. What the robot holds through
an attach joint widens the footprint it plans with.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import numpy as np
from py_trees.common import Status
from py_trees.ports import PortInformation

from bt_manip.behaviours.base import ActionFailed, RobotAction, WorldAccess
from bt_manip.behaviours.collisions import carried_collisions
from bt_manip.bt import registry
from bt_manip.bt.ports import NON_NEGATIVE, POSITIVE, Accepts, Port
from bt_manip.navigation.controller import FollowState
from bt_manip.navigation.grid import GridTooLarge
from bt_manip.navigation.holonomic import HolonomicStatus
from bt_manip.navigation.navigator import Navigator
from bt_manip.run.faults import block_route
from bt_manip.sim import pybullet_queries as pbq

TIME_BUDGET_FACTOR = 1.5
"""Without a ``timeout``, Navigate allows this many times the time the path takes at full
speed..."""
TIME_BUDGET_MARGIN = 30.0
"""... plus this many sim seconds (turning on the spot, slowing down near the goal)."""


def synced_navigator(node: WorldAccess, robot: Any) -> Navigator:
    """The run's navigator of ``robot`` (one per robot and run), synced with the world; a grid
    too large to build makes the node fail with the reason."""
    name = node.robot_name_of(robot)
    try:
        nav = node.run_context.robot_services(name).navigator
    except GridTooLarge as exc:
        raise ActionFailed(str(exc)) from None
    return sync_navigator(node.world, name, nav)


def sync_navigator(world: Any, robot_name: str, nav: Navigator) -> Navigator:
    """``nav`` told the movable objects now in the world and what its robot now carries."""
    nav.movable = {b: n for n, b in world.movable.items()}
    held = {a.object_body: a.object_name for a in world.attachments.held_by(robot_name)}
    for body in [b for b in nav.attached if b not in held]:
        nav.detach(body)
    for body, label in held.items():
        if body not in nav.attached:
            nav.attach(body, label)
    return nav


def parse_goal(world: Any, text: str) -> tuple[float, float, float]:
    """A named pose of the world, or ``x;y;yaw``."""
    if text in world.poses:
        p = world.poses[text]
        return (p.x, p.y, p.yaw)
    parts = text.split(";")
    try:
        values = [float(v) for v in parts]
    except ValueError:
        values = []
    if len(values) != 3 or not all(math.isfinite(v) for v in values):
        known = ", ".join(sorted(world.poses)) or "none"
        raise ActionFailed(f"goal '{text}' is neither a named pose ({known}) nor x;y;yaw")
    return (values[0], values[1], values[2])


def goal_text_problem(text: Any) -> str | None:
    """What is wrong with a goal written as numbers (a pose name is checked at run time)."""
    if not isinstance(text, str) or ";" not in text:
        return None
    try:
        values = [float(v) for v in text.split(";")]
    except ValueError:
        values = []
    if len(values) != 3 or not all(math.isfinite(v) for v in values):
        return f"a goal written as numbers must be three finite numbers x;y;yaw, got '{text}'"
    return None


@registry.register
class Navigate(RobotAction):
    """Drives the base to ``goal`` (a named pose of the world, or ``x;y;yaw``). A holonomic
    base drives sideways as needed and turns to the goal heading on the way.

    - RUNNING while the base follows the planned path (re-planned when an object moves onto it);
    - SUCCESS when the base is within ``xy_tolerance`` (m) and ``yaw_tolerance`` (rad) of the
      goal;
    - FAILURE when there is no path (the reason says why: goal in an obstacle, no way wide
      enough for the footprint, ...), the base is stuck, ``timeout`` passes, a carried object
      touches a wall or furniture, or the robot runs into a movable object (it stops rather than
      push it; a retry plans around it).
    Halted: the base is braked where it is.
    """

    CARRIES = True
    INPUT_PORTS: dict[str, PortInformation] = {
        **RobotAction.INPUT_PORTS,
        "goal": Port(str, True, "named world pose, or x;y;yaw (m, rad; world)",
                     accepts=Accepts(check=goal_text_problem)),
        "xy_tolerance": Port(
            float, False, "distance to the goal that counts (m)", 0.1, POSITIVE
        ),
        "yaw_tolerance": Port(float, False, "heading error that counts (rad)", 0.1, POSITIVE),
        "timeout": Port(
            float, False, "sim seconds; 0 = from the path length", 0.0, NON_NEGATIVE
        ),
    }
    OUTPUT_PORTS: dict[str, PortInformation] = {
        "path_length": PortInformation(float, False, "length of the planned path (m)"),
    }

    def start(self) -> None:
        world = self.world
        robot = self.robot()
        if robot.description.base.type == "fixed":
            raise ActionFailed(f"{robot.description.name} has no mobile base")
        goal = parse_goal(world, self.get_input("goal"))
        nav = synced_navigator(self, robot)
        follower = dataclasses.replace(
            nav.options.follower,
            xy_tolerance=float(self.get_input("xy_tolerance")),
            yaw_tolerance=float(self.get_input("yaw_tolerance")),
        )
        plan = nav.start(self.believed_pose(robot), goal, follower=follower)
        if not plan.ok:
            raise ActionFailed(f"no path to {self.get_input('goal')}: {plan.reason}")
        self.nav = nav
        self.set_output("path_length", float(plan.length))
        timeout = float(self.get_input("timeout"))
        self.timeout = timeout or (
            TIME_BUDGET_FACTOR * plan.length / follower.max_speed + TIME_BUDGET_MARGIN
        )
        self._show(plan.polyline)
        faults = self.faults()
        if faults is not None:
            block_route(world, faults, plan.polyline, self.get_input("goal"))
        self.touching_at_start = set(self._bumped())  # it may drive away from these

    def step(self) -> Status:
        robot = self.robot()
        hits = carried_collisions(self.world, robot) + sorted(
            set(self._bumped()) - self.touching_at_start
        )
        if hits:
            robot.stop_base()
            raise ActionFailed("; ".join(hits))
        status = self.nav.update(self.believed_pose(robot), self.now())
        if status.state is FollowState.SUCCEEDED:
            robot.stop_base()
            return Status.SUCCESS
        if status.state is FollowState.FAILED:
            robot.stop_base()
            raise ActionFailed(status.reason)
        if self.elapsed() > self.timeout:
            robot.stop_base()
            x, y, _ = self.believed_pose(robot)
            raise ActionFailed(f"not there after {self.timeout:.0f} s (at x={x:.2f} y={y:.2f})")
        if isinstance(status, HolonomicStatus):
            robot.set_base_velocity(*status.velocity)
        else:
            robot.set_base_twist(*status.cmd)
        return Status.RUNNING

    def _bumped(self) -> list[str]:
        """Movable objects the robot (not its fingers' load) has run into: it does not push
        things out of its way, it stops so that a retry can plan around them."""
        world = self.world
        robot = self.robot()
        held = {a.object_body for a in world.attachments.held_by(self.robot_name())}
        fingers = robot.finger_link_ids
        # the contacts with each movable object asked for alone: the robot's many contacts
        # with the floor are not read every tick
        bumped = {
            name
            for name, body in world.movable.items()
            if body not in held
            and any(pt.link_a not in fingers for pt in pbq.contacts(world.client, robot.body, body))
        }
        return [f"ran into '{name}'" for name in sorted(bumped)]

    def on_halt(self) -> None:
        self._show(None)

    def _show(self, polyline: np.ndarray | None) -> None:
        if polyline is None:
            self.overlay.clear("base_plan")
        else:
            self.overlay.show_path("base_plan", np.asarray(polyline)[:, :2])


def base_contacts(world: Any, robot: Any, robot_name: str, drive_over: float = 0.0) -> set[str]:
    """Names of the bodies other than the floor that ``robot`` or the objects it holds touch
    now, leaving out bodies whose top is lower than ``drive_over`` (m) above the floor (what
    the base can drive over)."""
    ground = world.body_id("ground")
    mine = {robot.body} | {a.object_body for a in world.attachments.held_by(robot_name)}
    out = set()
    for body in mine:
        for other in pbq.touching(world.client, body):
            if other == ground or other in mine:
                continue
            if drive_over > 0.0 and pbq.aabb(world.client, other).upper[2] < drive_over:
                continue
            out.add(world.name_of(other) or str(other))
    return out

@registry.register
class Reverse(RobotAction):
    """Drives the base straight backwards by ``distance`` metres at ``speed`` (a recovery to
    get clear of an obstacle before planning again).

    - RUNNING while reversing;
    - SUCCESS once ``distance`` has been covered;
    - FAILURE when the robot or what it carries comes into contact with anything but the floor
      (it stops there), or it is not done after ``timeout`` s.
    Halted: the base is braked where it is.
    """

    INPUT_PORTS: dict[str, PortInformation] = {
        **RobotAction.INPUT_PORTS,
        "distance": Port(float, False, "how far to reverse (m)", 0.5, POSITIVE),
        "speed": Port(float, False, "reversing speed (m/s)", 0.2, POSITIVE),
        "timeout": Port(float, False, "sim seconds allowed", 10.0, POSITIVE),
    }

    def start(self) -> None:
        robot = self.robot()
        if robot.description.base.type == "fixed":
            raise ActionFailed(f"{robot.description.name} has no mobile base")
        self.distance = float(self.get_input("distance"))
        self.speed = abs(float(self.get_input("speed")))
        if self.distance <= 0 or self.speed <= 0:
            raise ActionFailed("distance and speed must be positive")
        self.origin = self.odom_pose(robot)
        self.touching = self._contacts()

    def _contacts(self) -> set[str]:
        """Bodies other than the floor that the robot or its load touch now."""
        return base_contacts(self.world, self.robot(), self.robot_name())

    def step(self) -> Status:
        robot = self.robot()
        new = self._contacts() - self.touching
        if new:
            robot.stop_base()
            raise ActionFailed("backing up, touched " + ", ".join(f"'{n}'" for n in sorted(new)))
        x, y, _ = self.odom_pose(robot)
        if math.hypot(x - self.origin[0], y - self.origin[1]) >= self.distance:
            robot.stop_base()
            return Status.SUCCESS
        if self.elapsed() > float(self.get_input("timeout")):
            robot.stop_base()
            raise ActionFailed(
                f"backed up only {math.hypot(x - self.origin[0], y - self.origin[1]):.2f} m"
            )
        robot.set_base_twist(-self.speed, 0.0)
        return Status.RUNNING
