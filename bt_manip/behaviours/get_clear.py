"""GetClear: a mobile base backs away from what it is up against, and finds another way out
when backing is blocked too.

A robot that ran into a crate, or is wedged between a crate and a wall, cannot plan its way
out: its footprint already touches the obstacle. :class:`GetClear` moves it by plain twists,
each checked against contacts as it goes, until it is ``distance`` away from everything it was
up against. The motions, in order: straight away from the obstacles (backwards when they are
ahead, forwards when they are behind), arcs away to either side, turns on the spot to either
side, then arcs the other way around them (driving forwards around a crate ahead). The turn
direction tried first is the one that swings the corner nearest the obstacles away from them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from py_trees.common import Status
from py_trees.ports import PortInformation

from bt_manip.behaviours.base import ActionFailed, RobotAction, skid_steer_refusal
from bt_manip.bt import registry
from bt_manip.bt.ports import Accepts, Port
from bt_manip.sim import pybullet_queries as pbq

TURN_RATE = 0.8
"""Yaw rate (rad/s) of the turning motions."""
TURN_ANGLE = math.pi / 4
"""How far (rad) one turn on the spot goes before the next motion is tried."""
STALL_WINDOW = 1.0
"""Sim seconds over which a motion must move the base to count as moving."""
STALL_MOVE = 0.01
"""Least translation (m) in :data:`STALL_WINDOW`..."""
STALL_TURN = 0.02
"""... or least turn (rad) in it; less is a blocked motion."""
PUSH_LIMIT = 0.05
"""A movable obstacle shoved this far (m) blocks the motion: the robot gets clear, it does not
push things out of its way."""
TOUCH = 0.01
"""Points of the robot this close (m) to an obstacle count as touching it: a motion that
drives one of them into the obstacle is not tried."""
PUSH_SLOPE = 0.3
"""A motion that moves a touching point into the obstacle at more than this fraction of the
point's speed (about 17 deg off sliding along it) would push it."""
PROGRESS = 0.05
"""Gap (m) a motion must have opened by the end of its time to be kept on rather than
replaced by the motions planned afresh."""
MAX_MOTIONS = 12
"""Motions tried at most before the node gives up."""


@dataclass(frozen=True)
class Motion:
    """A twist held until the robot is clear, the motion is blocked, or ``duration`` passes."""

    name: str
    v: float
    w: float
    duration: float


def _pose_delta(
    a: tuple[float, float, float], b: tuple[float, float, float]
) -> tuple[float, float]:
    turn = abs(math.atan2(math.sin(b[2] - a[2]), math.cos(b[2] - a[2])))
    return math.hypot(b[0] - a[0], b[1] - a[1]), turn


@registry.register
class GetClear(RobotAction):
    """Gets the robot's base clear of what it (or the object it carries) is up against.

    What it gets clear of: every body but the floor within ``near`` (5 cm by default) of the
    robot or its load when the node starts (a planner that keeps a margin from obstacles may
    need a larger ``near``). It then drives plain twists (see the module), one after the other,
    each checked as it goes: a motion is blocked when the robot or its load touches anything it
    was not already up against, shoves a movable obstacle more than 5 cm, or stops moving (less
    than 1 cm or 0.02 rad in 1 s).

    - RUNNING while it moves;
    - SUCCESS once every one of those bodies is at least ``distance`` away (at once, with
      "nothing to get clear of", when nothing is within ``near``);
    - FAILURE when every motion is blocked (the reason lists what blocked each), or after
      ``timeout`` s, or the robot has no mobile base; the base is braked.
    Halted: the base is braked where it is.
    """

    INPUT_PORTS: dict[str, PortInformation] = {
        **RobotAction.INPUT_PORTS,
        "distance": Port(
            float, False, "clearance to reach (m)", 0.5, Accepts(low=0, high=5, low_open=True)
        ),
        "speed": Port(
            float, False, "driving speed (m/s)", 0.2, Accepts(low=0, high=1, low_open=True)
        ),
        "near": Port(
            float, False, "what is this close (m) at the start is got clear of", 0.05,
            Accepts(low=0, high=1, low_open=True),
        ),
        "timeout": Port(
            float, False, "sim seconds allowed", 30.0, Accepts(low=0, high=600, low_open=True)
        ),
    }

    def start(self) -> None:
        robot = self.robot()
        refusal = skid_steer_refusal(robot, "GetClear")
        if refusal is not None:
            raise ActionFailed(refusal)
        self.distance = float(self.get_input("distance"))
        self.speed = float(self.get_input("speed"))
        self.timeout = float(self.get_input("timeout"))
        self.mine = self._mine()
        self.obstacles = self._near(float(self.get_input("near")))
        world = self.world
        movable = set(world.movable.values())
        self.anchors = {b: self._position(b) for b in self.obstacles if b in movable}
        self.blocked: list[str] = []
        self.motion_started = 0.0
        self.gap_at_start = 0.0
        self.tried = 0
        self.queue: list[Motion] = self._motions() if self.obstacles else []
        self.motion: Motion | None = None

    # -- what the robot is and what is around it ---------------------------------------------
    def _mine(self) -> set[int]:
        robot = self.robot()
        held = self.world.attachments.held_by(self.robot_name())
        return {robot.body} | {a.object_body for a in held}

    def _near(self, within: float) -> dict[int, str]:
        """Bodies other than the floor and the robot's own within ``within`` of it or its load."""
        world = self.world
        ground = world.body_id("ground")
        out: dict[int, str] = {}
        for info in world.infos.values():
            if info.body_id == ground or info.body_id in self.mine:
                continue
            if any(pbq.closest_points(world.client, m, info.body_id, within) for m in self.mine):
                out[info.body_id] = info.name
        return out

    def _position(self, body: int) -> np.ndarray:
        pos, _ = pbq.com_pose(self.world.client, body, -1)
        return np.asarray(pos, dtype=float)

    def _still_near(self) -> list[str]:
        """The obstacles not yet ``distance`` away."""
        c = self.world.client
        return [
            name
            for body, name in self.obstacles.items()
            if any(pbq.closest_points(c, m, body, self.distance) for m in self.mine)
        ]

    def _touch_points(self, within: float) -> list[tuple[float, float, float, float, str]]:
        """Where the robot or its load comes within ``within`` of an obstacle: (x, y) of the
        point and (nx, ny) pointing into the obstacle, in the robot's frame (x ahead, y left),
        and the obstacle's name."""
        c = self.world.client
        x0, y0, yaw = self.robot().base_pose2d()
        cy, sy = math.cos(yaw), math.sin(yaw)
        out = []
        for m in self.mine:
            for body, name in self.obstacles.items():
                for p in pbq.closest_points(c, m, body, within):
                    dx, dy = p.position_on_a[0] - x0, p.position_on_a[1] - y0
                    nx, ny = -p.normal_on_b[0], -p.normal_on_b[1]
                    out.append(
                        (cy * dx + sy * dy, -sy * dx + cy * dy, cy * nx + sy * ny,
                         -sy * nx + cy * ny, name)
                    )
        return out

    def _pushes_into(
        self, motion: Motion, points: list[tuple[float, float, float, float, str]]
    ) -> list[str]:
        """Obstacles the motion would drive a touching point of the robot into."""
        hit = set()
        for px, py, nx, ny, name in points:
            vx, vy = motion.v - motion.w * py, motion.w * px
            if vx * nx + vy * ny > PUSH_SLOPE * math.hypot(vx, vy):
                hit.add(name)
        return sorted(hit)

    def _motions(self) -> list[Motion]:
        """The motions to try from here, in order (see the module); the ones that would drive
        the robot into something it touches are left out and noted in ``self.blocked``."""
        points = self._touch_points(TOUCH)
        near = self._touch_points(self.distance)
        ahead = float(np.mean([p[0] for p in near])) if near else 1.0
        left = float(np.mean([p[1] for p in near])) if near else 0.0
        away = -1.0 if ahead >= 0.0 else 1.0  # drive away from the obstacles' end
        # turning this way swings the robot's end nearest the obstacles away from their side
        turn = -math.copysign(1.0, left) * math.copysign(1.0, ahead) if left else 1.0
        v, w = self.speed, TURN_RATE
        straight = self.distance / v + STALL_WINDOW
        arc = min(straight, (math.pi / 2) / w)
        turning = TURN_ANGLE / w + STALL_WINDOW / 2
        towards = "forwards" if away < 0 else "backwards"
        motions = [
            Motion("backing away" if away < 0 else "driving away", away * v, 0.0, straight),
            Motion("arcing away", away * v, turn * w, arc),
            Motion("arcing away the other side", away * v, -turn * w, arc),
            Motion("turning on the spot", 0.0, turn * w, turning),
            Motion("turning on the spot the other way", 0.0, -turn * w, turning),
            Motion(f"driving {towards} past", -away * v, 0.0, straight),
            Motion(f"driving {towards} around", -away * v, turn * w, arc),
            Motion(f"driving {towards} around the other side", -away * v, -turn * w, arc),
        ]
        out = []
        for motion in motions:
            into = self._pushes_into(motion, points)
            if into:
                self._note(f"{motion.name} would push into " + ", ".join(f"'{n}'" for n in into))
            else:
                out.append(motion)
        return out

    def _note(self, why: str) -> None:
        if why not in self.blocked:
            self.blocked.append(why)

    # -- ticking -------------------------------------------------------------------------------
    def step(self) -> Status:
        robot = self.robot()
        if not self.obstacles:
            self.feedback_message = "nothing to get clear of"
            return Status.SUCCESS
        if not self._still_near():
            robot.stop_base()
            names = ", ".join(f"'{n}'" for n in sorted(self.obstacles.values()))
            self.feedback_message = f"clear of {names} by {self.distance:g} m"
            return Status.SUCCESS
        if self.elapsed() > self.timeout:
            robot.stop_base()
            raise ActionFailed(f"not clear after {self.timeout:g} s: {self._summary()}")
        if self.motion is not None:
            why = self._blocked_by()
            if why is not None:
                robot.stop_base()
                self._note(f"{self.motion.name} {why}")
                self.motion = None
            elif self.now() - self.motion_started > self.motion.duration:
                gained = self._gap() - self.gap_at_start
                same = self.motion
                self.motion = None
                self.queue = self._motions()  # it moved: plan again from here
                if gained >= PROGRESS and same in self.queue:  # it is working: keep on
                    self.queue.remove(same)
                    self.queue.insert(0, same)
        if self.motion is None:
            if not self.queue or self.tried >= MAX_MOTIONS:
                robot.stop_base()
                raise ActionFailed(f"no motion frees it: {self._summary()}")
            self.motion = self.queue.pop(0)
            self.tried += 1
            self.motion_started = self.now()
            self.window = (self.now(), robot.base_pose2d())
            self.touching = self._touching()
            self.anchors = {b: self._position(b) for b in self.anchors}
            self.gap_at_start = self._gap()
        robot.set_base_twist(self.motion.v, self.motion.w)
        self.feedback_message = f"{self.motion.name} (from {', '.join(self._still_near())})"
        return Status.RUNNING

    def _gap(self) -> float:
        """The smallest gap (m) between the robot or its load and the obstacles, counted up to
        ``distance``."""
        c = self.world.client
        gaps = [
            p.distance
            for m in self.mine
            for body in self.obstacles
            for p in pbq.closest_points(c, m, body, self.distance)
        ]
        return min(gaps, default=self.distance)

    def _summary(self) -> str:
        still = ", ".join(f"'{n}'" for n in self._still_near())
        tried = "; ".join(self.blocked) or "no motion was blocked"
        return f"still within {self.distance:g} m of {still} ({tried})"

    def _touching(self) -> set[int]:
        c = self.world.client
        ground = self.world.body_id("ground")
        return {
            other
            for m in self.mine
            for other in pbq.touching(c, m)
            if other != ground and other not in self.mine
        }

    def _blocked_by(self) -> str | None:
        """Why the current motion cannot go on, or None."""
        world = self.world
        new = self._touching() - set(self.obstacles) - self.touching
        if new:
            names = sorted(world.name_of(b) or str(b) for b in new)
            return "touched " + ", ".join(f"'{n}'" for n in names)
        for body, anchor in self.anchors.items():
            if np.linalg.norm(self._position(body)[:2] - anchor[:2]) > PUSH_LIMIT:
                return f"pushed '{self.obstacles[body]}'"
        t0, pose0 = self.window
        if self.now() - t0 >= STALL_WINDOW:
            moved, turned = _pose_delta(pose0, self.robot().base_pose2d())
            if moved < STALL_MOVE and turned < STALL_TURN:
                return "is stuck (the base does not move)"
            self.window = (self.now(), self.robot().base_pose2d())
        return None

    def on_halt(self) -> None:
        self.motion = None
