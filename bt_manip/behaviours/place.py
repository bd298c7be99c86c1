"""Place: put the object in the hand down at a target pose, by IK, with a straight final motion.

The object is held through an attach joint (:mod:`bt_manip.behaviours.attach`), so where the
hand must go follows from where the object is in the hand now: the grasp frame's target is the
object's target pose composed with the inverse of the object's pose in the grasp frame. Of the
two turns of the target that are the same box (:mod:`bt_manip.manipulation.placing`), the one
nearer the hand's orientation now is tried first.

The move has two parts: a joint move to the pre-place point, ``approach`` metres straight above
the target, and the final motion, a straight line down to the target (left ``gap`` metres
above it, so the object is set down, not pushed into the floor). Until the final motion starts
the carried object may touch nothing at all (walls, furniture, floor, other objects): a touch
is a failure with its reason, and so is any touch recorded while the object was carried before
Place started. During the final motion it may touch walls, furniture and the floor (what it is
set on or against), not other objects; the arm itself may touch none of them.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from py_trees.common import Status
from py_trees.ports import PortInformation

from bt_manip.behaviours.arm import VIA, JointMove, Stage, _through
from bt_manip.behaviours.base import ActionFailed
from bt_manip.behaviours.collisions import arm_link_ids
from bt_manip.bt import registry
from bt_manip.bt.ports import Accepts, Port
from bt_manip.manipulation import cartesian
from bt_manip.manipulation.cartesian import CartesianError
from bt_manip.manipulation.perception import true_pose
from bt_manip.manipulation.placing import (
    Deviation,
    Target,
    TargetError,
    deviation,
    lifted,
    parse_target,
    place_frames,
    target_problem,
    yaw_of_matrix,
)
from bt_manip.sim import pybullet_queries as pbq

DEFAULT_POSITION_TOLERANCE = 0.02
"""Largest distance (m) of a placed object's centre from its target."""
DEFAULT_ANGLE_TOLERANCE = 2.0
"""Largest rotation (deg) of a placed object from its target."""
DEFAULT_APPROACH = 0.1
"""Length (m) of the straight final motion down to the target."""
DEFAULT_GAP = 0.002
"""Height (m) above the target where the final motion ends."""

TARGET = Port(
    str, True, "target pose of the object's centre x;y;z;yaw (m, rad; world)", "",
    Accepts(check=target_problem),
)
POSITION_TOLERANCE = Port(
    float, False, "largest distance of the object's centre from the target (m)",
    DEFAULT_POSITION_TOLERANCE, Accepts(0.0, 0.2, low_open=True),
)
ANGLE_TOLERANCE = Port(
    float, False, "largest rotation of the object from the target (deg)",
    DEFAULT_ANGLE_TOLERANCE, Accepts(0.0, 45.0, low_open=True),
)
OBJECT = PortInformation(str, True, "name of the movable object held (attached) by the robot")
APPROACH = Port(
    float, False, "length of the straight final motion down (m)", DEFAULT_APPROACH,
    Accepts(0.02, 0.3),
)


def read_target(node: Any) -> Target:
    """The node's ``target`` port as a Target; ActionFailed with the reason otherwise."""
    try:
        return parse_target(node.get_input("target"))
    except TargetError as exc:
        raise ActionFailed(str(exc)) from None


def tolerance_problem(node: Any, name: str, dev: Deviation, target: Target) -> str | None:
    """Why object ``name``, ``dev`` from ``target``, is outside the node's
    ``position_tolerance`` / ``angle_tolerance`` ports; None when it is within them."""
    pos_tol = float(node.get_input("position_tolerance"))
    ang_tol = math.radians(float(node.get_input("angle_tolerance")))
    if dev.within(pos_tol, ang_tol):
        return None
    return (
        f"'{name}' is {dev.text()} from its target {target.text()} (tolerance "
        f"{pos_tol * 1000:g} mm and {math.degrees(ang_tol):g} deg)"
    )


def held_body(node: Any, name: str) -> int:
    """PyBullet id of object ``name`` when the node's robot holds it through an attach joint;
    ActionFailed otherwise."""
    body = node.object_body(name)
    if not node.world.attachments.is_attached(name, node.robot_name()):
        raise ActionFailed(f"the robot does not hold '{name}' (attach it first)")
    return int(body)


def static_names(world: Any) -> dict[int, str]:
    """Walls, furniture and the floor by body id."""
    return {
        i.body_id: i.name for i in world.infos.values() if i.kind in ("wall", "furniture", "ground")
    }


def touches(world: Any, body: int, ignore: int) -> dict[int, str]:
    """Bodies ``body`` touches now (``ignore`` and itself left out), by id with their names."""
    out = {}
    for c in pbq.contacts(world.client, body):
        if c.body_b not in (body, ignore):
            out[c.body_b] = world.name_of(c.body_b) or f"body {c.body_b}"
    return out


@registry.register
class Place(JointMove):
    """Puts the held ``object`` at ``target`` (``x;y;z;yaw`` of its centre): a joint move to
    ``approach`` m above the target, then a straight line down, checked on the way.

    - RUNNING while the arm moves;
    - SUCCESS when the arm has arrived and the object's true pose is within
      ``position_tolerance`` (m) and ``angle_tolerance`` (deg) of the target; ``placed_pose``,
      ``deviation_mm`` and ``deviation_deg`` are set;
    - FAILURE, with the reason, when the robot does not hold the object, no arm configuration
      reaches the pre-place point or the line down (unreachable), the object touched anything
      while carried or before the final motion, it touches another object or the arm touches
      a wall, furniture or the floor during the final motion, a joint times out, or the placed
      object is out of tolerance (the deviation outputs are set then too); before the arm
      moves, when the way there (checked in the arm's planning scene) would bring the arm or the
      object against a wall, furniture or the floor, naming what.
    Halted: the arm holds where it is, with the object still in the hand.
    """

    CARRIES = True
    LINE_CHECK = True
    LINE_NAME = "the move to the place"
    INPUT_PORTS: dict[str, PortInformation] = {
        **JointMove.INPUT_PORTS,
        "object": OBJECT,
        "target": TARGET,
        "approach": APPROACH,
        "gap": Port(
            float, False, "height above the target where the final motion ends (m)",
            DEFAULT_GAP, Accepts(0.0, 0.02),
        ),
        "position_tolerance": POSITION_TOLERANCE,
        "angle_tolerance": ANGLE_TOLERANCE,
        "via_tolerance": VIA,
    }
    OUTPUT_PORTS: dict[str, PortInformation] = {
        "placed_pose": PortInformation(str, False, "the object's pose now x;y;z;yaw"),
        "deviation_mm": PortInformation(float, False, "distance from the target (mm)"),
        "deviation_deg": PortInformation(float, False, "rotation from the target (deg)"),
    }

    def plan(self, q_now: np.ndarray) -> list[Stage]:
        robot = self.robot()
        name = self.get_input("object")
        body = held_body(self, name)
        touched = self.world.attachments.touched(name)
        if touched:
            raise ActionFailed(
                f"'{name}' touched {', '.join(repr(t) for t in touched)} while carried, before "
                "the final placing motion"
            )
        self.target = read_target(self)
        tip = robot.description.grasp_frame
        hand = robot.link_transform(tip)
        object_in_grasp = np.linalg.inv(hand) @ true_pose(self.world, body)
        approach = float(self.get_input("approach"))
        gap = float(self.get_input("gap"))
        services = self.services()
        n = len(q_now)
        reasons = []
        # the target is in the map frame: the arm aims where the robot believes it is, so the
        # localisation's error carries over (none without localisation)
        x, y, yaw = self.map_to_world((self.target.x, self.target.y, self.target.yaw))
        aim = Target(x, y, self.target.z, yaw)
        for frame in place_frames(aim, object_in_grasp, hand):
            goal = lifted(frame, gap)
            pre = lifted(goal, approach)
            self.overlay.show_frame("ik_target", goal)
            try:
                q_pre = cartesian.solve(services, tip, pre, q_now)
                down = cartesian.line(services, tip, pre, goal, q_pre)
            except CartesianError as exc:
                reasons.append(str(exc))
                continue
            self.final_from = 1
            return [Stage(q_pre, list(range(n))), *_through(down, n)]
        raise ActionFailed(
            f"cannot place '{name}' at {self.target.text()}: unreachable ("
            + "; ".join(dict.fromkeys(reasons)) + ")"
        )

    def start(self) -> None:
        self.final_from = 0
        super().start()
        self.watch_arm = self.check
        self.check = False  # the checks of this node replace JointMove's
        self.name_held = self.get_input("object")
        self.body_held = self.object_body(self.name_held)
        robot = self.robot()
        self.static = static_names(self.world)
        self.arm_links = arm_link_ids(robot)
        self.initial_arm = self._arm_touches(robot)

    def _arm_touches(self, robot: Any) -> set[str]:
        found = set()
        for c in pbq.contacts(self.world.client, robot.body):
            if c.link_a in self.arm_links and c.body_b in self.static:
                found.add(f"{robot.link_name(c.link_a)} touched '{self.static[c.body_b]}'")
        return found

    def step(self) -> Status:
        robot = self.robot()
        name = self.name_held
        if not self.world.attachments.is_attached(name, self.robot_name()):
            robot.hold_arm()
            raise ActionFailed(f"'{name}' is no longer held")
        if self.watch_arm:
            hits = sorted(self._arm_touches(robot) - self.initial_arm)
            if hits:
                robot.hold_arm()
                raise ActionFailed("placing: " + "; ".join(hits))
        final = self.stage >= self.final_from
        now = touches(self.world, self.body_held, robot.body)
        if not final and now:
            robot.hold_arm()
            raise ActionFailed(
                f"'{name}' touched {', '.join(repr(v) for v in sorted(now.values()))} before the "
                "final placing motion"
            )
        others = sorted(v for b, v in now.items() if b not in self.static)
        if final and others:
            robot.hold_arm()
            raise ActionFailed(
                f"'{name}' touched {', '.join(repr(v) for v in others)} while set down"
            )
        status = super().step()
        if status != Status.SUCCESS:
            return status
        pose = true_pose(self.world, self.body_held)
        dev = deviation(pose, self.target)
        self._report(pose, dev)
        problem = tolerance_problem(self, name, dev, self.target)
        if problem is not None:
            raise ActionFailed(problem)
        self.feedback_message = f"placed '{name}' {dev.text()} from its target"
        return Status.SUCCESS

    def _report(self, pose: np.ndarray, dev: Deviation) -> None:
        x, y, z = (float(v) for v in pose[:3, 3])
        self.set_output("placed_pose", f"{x:.4f};{y:.4f};{z:.4f};{yaw_of_matrix(pose):.4f}")
        self.set_output("deviation_mm", round(dev.mm, 2))
        self.set_output("deviation_deg", round(dev.deg, 3))
