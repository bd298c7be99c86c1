"""Navigate: drive the mobile base to a pose through the world's rooms.

The path is planned on an occupancy grid of the world (A*; over poses while something long is
carried) and followed by the base controller, one twist per tick. What the robot holds through
an attach joint widens the footprint it plans with.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any, ClassVar

import numpy as np
from py_trees.common import Status
from py_trees.ports import PortInformation

from bt_manip.behaviours.base import ActionFailed, RobotAction
from bt_manip.behaviours.collisions import carried_collisions
from bt_manip.bt import registry
from bt_manip.bt.ports import NON_NEGATIVE, POSITIVE, Accepts, Port
from bt_manip.navigation.controller import FollowState
from bt_manip.navigation.grid import GridTooLarge
from bt_manip.navigation.navigator import Navigator
from bt_manip.sim import pybullet_queries as pbq
from bt_manip.sim.world_spec import COLOURS, BodySpec, Part, Pose3D, Range2D

BLOCK_SIZE = 0.3
"""Side (m) of the crate an injected ``block`` fault drops on the route."""
BLOCK_CLEARANCE = 1.5
"""The crate falls at least this far (m) from the route's start and its goal."""


def navigator_for(world: Any, robot: Any) -> Navigator:
    """The robot's navigator (one per robot, kept on its handle), synced with the world: the
    movable objects now in it and what the robot now carries."""
    nav: Navigator | None = robot.__dict__.get("_navigator")
    if nav is None:
        try:
            nav = Navigator(robot, world.obstacle_body_ids(), world.movable)
        except GridTooLarge as exc:
            raise ActionFailed(str(exc)) from None
        robot.__dict__["_navigator"] = nav
    nav.movable = {b: n for n, b in world.movable.items()}
    name = next((n for n, r in world.robots.items() if r is robot), "")
    held = {a.object_body: a.object_name for a in world.attachments.held_by(name)}
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


def _goal_text(text: Any) -> str | None:
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
    """Drives the base to ``goal`` (a named pose of the world, or ``x;y;yaw``).

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
    INPUT_PORTS: ClassVar[dict[str, PortInformation]] = {
        **RobotAction.INPUT_PORTS,
        "goal": Port(str, True, "named world pose, or x;y;yaw", accepts=Accepts(check=_goal_text)),
        "xy_tolerance": Port(
            float, False, "distance to the goal that counts (m)", 0.1, POSITIVE
        ),
        "yaw_tolerance": Port(float, False, "heading error that counts (rad)", 0.1, POSITIVE),
        "timeout": Port(
            float, False, "sim seconds; 0 = from the path length", 0.0, NON_NEGATIVE
        ),
    }
    OUTPUT_PORTS: ClassVar[dict[str, PortInformation]] = {
        "path_length": PortInformation(float, False, "length of the planned path (m)"),
    }

    def start(self) -> None:
        world = self.world
        robot = self.robot()
        if robot.description.base.type != "skid_steer":
            raise ActionFailed(f"{robot.description.name} has no mobile base")
        goal = parse_goal(world, self.get_input("goal"))
        nav = navigator_for(world, robot)
        follower = dataclasses.replace(
            nav.options.follower,
            xy_tolerance=float(self.get_input("xy_tolerance")),
            yaw_tolerance=float(self.get_input("yaw_tolerance")),
        )
        nav.options = dataclasses.replace(nav.options, follower=follower)
        plan = nav.start(robot.base_pose2d(), goal)
        if not plan.ok:
            raise ActionFailed(f"no path to {self.get_input('goal')}: {plan.reason}")
        self.nav = nav
        self.set_output("path_length", float(plan.length))
        timeout = float(self.get_input("timeout"))
        self.timeout = timeout or 1.5 * plan.length / follower.max_speed + 30.0
        self._show(plan.polyline)
        self._maybe_block(plan.polyline)
        self.touching_at_start = set(self._bumped())  # it may drive away from these

    def step(self) -> Status:
        robot = self.robot()
        hits = carried_collisions(self.world, robot) + sorted(
            set(self._bumped()) - self.touching_at_start
        )
        if hits:
            robot.stop_base()
            raise ActionFailed("; ".join(hits))
        status = self.nav.update(robot.base_pose2d(), self.now())
        if status.state is FollowState.SUCCEEDED:
            robot.stop_base()
            return Status.SUCCESS
        if status.state is FollowState.FAILED:
            robot.stop_base()
            raise ActionFailed(status.reason)
        if self.elapsed() > self.timeout:
            robot.stop_base()
            x, y, _ = robot.base_pose2d()
            raise ActionFailed(f"not there after {self.timeout:.0f} s (at x={x:.2f} y={y:.2f})")
        robot.set_base_twist(*status.cmd)
        return Status.RUNNING

    def _bumped(self) -> list[str]:
        """Movable objects the robot (not its fingers' load) has run into: it does not push
        things out of its way, it stops so that a retry can plan around them."""
        world = self.world
        robot = self.robot()
        held = {a.object_body for a in world.attachments.held_by(self.robot_name())}
        movable = {b: n for n, b in world.movable.items() if b not in held}
        bumped = {
            movable[pt.body_b]
            for pt in pbq.contacts(world.client, robot.body)
            if pt.body_b in movable and pt.link_a not in robot.finger_link_ids
        }
        return [f"ran into '{name}'" for name in sorted(bumped)]

    def on_halt(self) -> None:
        self._show(None)

    def _show(self, polyline: np.ndarray | None) -> None:
        from bt_manip.viz.overlay import overlay_for

        overlay = overlay_for(self.world)
        if polyline is None:
            overlay.clear("base_plan")
        else:
            overlay.show_path("base_plan", np.asarray(polyline)[:, :2])

    def _maybe_block(self, polyline: np.ndarray) -> None:
        """The ``block`` fault: a crate falls on the route, at the middle point of the route
        that is at least :data:`BLOCK_CLEARANCE` from both ends (a route with no such point
        gets none): it tests going around an obstacle, not a goal made unreachable."""
        faults = self.faults()
        if faults is None or not faults.specs or polyline is None or len(polyline) < 2:
            return
        pts = np.asarray(polyline)[:, :2]
        far = (np.linalg.norm(pts - pts[0], axis=1) >= BLOCK_CLEARANCE) & (
            np.linalg.norm(pts - pts[-1], axis=1) >= BLOCK_CLEARANCE
        )
        if not far.any() or not faults.block(self.get_input("goal")):
            return
        candidates = np.flatnonzero(far)
        x, y = pts[candidates[len(candidates) // 2]]
        n = sum(1 for name in self.world.movable if name.startswith("dropped_crate"))
        spec = BodySpec(
            name=f"dropped_crate_{n}",
            movable=True,
            parts=[Part("box", (BLOCK_SIZE,) * 3, colour=COLOURS["brown"])],
            urdf=None,
            pose=Pose3D((float(x), float(y), BLOCK_SIZE / 2 + 0.3)),
            planar=False,
            mass=8.0,
            friction=0.9,
            colour=COLOURS["brown"],
            randomize=Range2D(),
            line=0,
        )
        try:
            self.world.spawn(spec)
        except ValueError:
            return


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

    INPUT_PORTS: ClassVar[dict[str, PortInformation]] = {
        **RobotAction.INPUT_PORTS,
        "distance": Port(float, False, "how far to reverse (m)", 0.5, POSITIVE),
        "speed": Port(float, False, "reversing speed (m/s)", 0.2, POSITIVE),
        "timeout": Port(float, False, "sim seconds allowed", 10.0, POSITIVE),
    }

    def start(self) -> None:
        robot = self.robot()
        if robot.description.base.type != "skid_steer":
            raise ActionFailed(f"{robot.description.name} has no mobile base")
        self.distance = float(self.get_input("distance"))
        self.speed = abs(float(self.get_input("speed")))
        if self.distance <= 0 or self.speed <= 0:
            raise ActionFailed("distance and speed must be positive")
        self.origin = robot.base_pose2d()
        self.touching = self._contacts()

    def _contacts(self) -> set[str]:
        """Bodies other than the floor that the robot or its load touch now."""
        world = self.world
        robot = self.robot()
        ground = world.body_id("ground")
        mine = {robot.body} | {a.object_body for a in world.attachments.held_by(self.robot_name())}
        out = set()
        for body in mine:
            for other in pbq.touching(world.client, body):
                if other != ground and other not in mine:
                    out.add(world.name_of(other) or str(other))
        return out

    def step(self) -> Status:
        robot = self.robot()
        new = self._contacts() - self.touching
        if new:
            robot.stop_base()
            raise ActionFailed("backing up, touched " + ", ".join(f"'{n}'" for n in sorted(new)))
        x, y, _ = robot.base_pose2d()
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
