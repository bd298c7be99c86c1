"""Arm behaviours in joint space: one joint at a time, all together, and lifting by deltas.

Each commands the arm's position controllers and returns RUNNING until the joints are within
tolerance; none blocks. Targets outside the joint limits, a joint that does not arrive within
its time-out (sim time), and contact between the arm (or what it carries) and the static world
end the move with FAILURE and a reason; the arm then holds where it is.
"""

from __future__ import annotations

import math
from typing import ClassVar

import numpy as np
from py_trees.common import Status
from py_trees.ports import PortInformation

from bt_manip.behaviours.base import ActionFailed, RobotAction
from bt_manip.behaviours.collisions import arm_collisions
from bt_manip.bt import registry

UNITS = PortInformation(str, False, "unit of targets: deg or rad", "deg")
TOLERANCE = PortInformation(float, False, "how close each joint must get (rad)", 0.01)
SPEED = PortInformation(float, False, "fraction of each joint's velocity limit, 0..1", 0.5)
TIMEOUT = PortInformation(float, False, "sim seconds allowed per joint move", 10.0)
CHECK = PortInformation(bool, False, "fail when the arm touches walls, furniture or floor", True)
SETTLE_SPEED = 0.05
"""A joint counts as arrived when within tolerance and slower than this (rad/s)."""


def to_radians(values: list[float], units: str) -> np.ndarray:
    if units not in ("deg", "rad"):
        raise ActionFailed(f"units must be 'deg' or 'rad', got '{units}'")
    a = np.asarray(values, dtype=float)
    return np.radians(a) if units == "deg" else a


def _fmt(q: float, units: str) -> str:
    return f"{math.degrees(q):.1f} deg" if units == "deg" else f"{q:.3f} rad"


class JointMove(RobotAction):
    """Shared machinery: a list of stages, each moving some joints to their targets."""

    INPUT_PORTS: ClassVar[dict[str, PortInformation]] = {
        **RobotAction.INPUT_PORTS,
        "units": UNITS,
        "tolerance": TOLERANCE,
        "speed": SPEED,
        "joint_timeout": TIMEOUT,
        "check_collisions": CHECK,
    }

    def plan(self, q_now: np.ndarray) -> tuple[np.ndarray, list[list[int]]]:
        """Final targets (rad, all arm joints) and the stages: lists of joints moved together."""
        raise NotImplementedError

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
        arm = robot.description.arm
        q_now = robot.arm_positions()
        targets, stages = self.plan(q_now)
        lower = np.asarray(arm.lower, dtype=float)
        upper = np.asarray(arm.upper, dtype=float)
        for j in sorted({j for stage in stages for j in stage}):
            if not lower[j] - 1e-9 <= targets[j] <= upper[j] + 1e-9:
                raise ActionFailed(
                    f"joint {j} ({arm.joints[j]}) target {_fmt(targets[j], self.units)} is "
                    f"outside its limits [{_fmt(lower[j], self.units)}, "
                    f"{_fmt(upper[j], self.units)}]"
                )
        self.targets = targets
        self.stages = [s for s in stages if s]
        self.command = q_now.copy()
        self.stage = -1
        self._next_stage(robot)

    def _next_stage(self, robot: object) -> None:
        self.stage += 1
        self.stage_started = self.now()
        if self.stage >= len(self.stages):
            return
        joints = self.stages[self.stage]
        q = self.robot().arm_positions()
        vmax = np.asarray(self.robot().description.arm.velocity_limits, dtype=float) * self.speed
        self.command[joints] = self.targets[joints]
        # joints moved together arrive together: scale each speed to the slowest travel time
        travel = np.abs(self.targets[joints] - q[joints])
        t = float(np.max(travel / vmax[joints])) if len(joints) else 0.0
        self._send(joints, travel, t)

    def _send(self, joints: list[int], travel: np.ndarray, t: float) -> None:
        """Command the stage. The moving joints get speeds that make them arrive together;
        every joint may correct at no less than a fifth of its allowed speed, so a joint that
        a load pushes away can come back."""
        robot = self.robot()
        vmax = np.asarray(robot.description.arm.velocity_limits, dtype=float) * self.speed
        floor = 0.2 * vmax
        speeds = floor.copy()
        if t > 1e-9:
            speeds[joints] = np.maximum(travel / t, floor[joints])
        else:
            speeds[joints] = vmax[joints]
        robot.set_arm_targets(self.command, max_velocity=speeds)

    def step(self) -> Status:
        robot = self.robot()
        if self.check:
            hits = arm_collisions(self.world, robot)
            if hits:
                robot.hold_arm()
                raise ActionFailed(self._where() + ": " + "; ".join(hits))
        if self.stage >= len(self.stages):
            return Status.SUCCESS
        # every joint, not only the moving ones, must be where it was told to be: a load can
        # push a holding joint away, and the move is not done until it is back
        q = robot.arm_positions()
        qd = robot.arm_velocities()
        err = np.abs(q - self.command)
        if np.all(err < self.tol) and np.all(np.abs(qd) < SETTLE_SPEED):
            self._next_stage(robot)
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
        joints = self.stages[self.stage] if 0 <= self.stage < len(self.stages) else []
        return f"moving joint {joints[0]}" if len(joints) == 1 else "moving the arm"


@registry.register
class MoveJointsSequentially(JointMove):
    """Moves arm joints to their targets ONE AT A TIME, in the given order.

    - RUNNING while a joint moves (the others hold their positions);
    - SUCCESS when every joint named in ``order`` has reached its target within ``tolerance``;
    - FAILURE when a target is outside its joint limits, a joint does not arrive within
      ``joint_timeout`` s, or the arm (or what it carries) touches a wall, furniture or the floor.
    Halted: the arm holds where it is.
    """

    INPUT_PORTS: ClassVar[dict[str, PortInformation]] = {
        **JointMove.INPUT_PORTS,
        "targets": PortInformation(list[float], True, "joint targets, one per arm joint"),
        "order": PortInformation(
            list[int], False, "joint indices in the order to move them (empty: 0, 1, ...)", []
        ),
    }

    def plan(self, q_now: np.ndarray) -> tuple[np.ndarray, list[list[int]]]:
        targets = to_radians(self.get_input("targets"), self.get_input("units"))
        n = len(q_now)
        if len(targets) != n:
            raise ActionFailed(f"targets has {len(targets)} values; the arm has {n} joints")
        order = list(self.get_input("order")) or list(range(n))
        bad = [j for j in order if not 0 <= j < n]
        if bad or len(set(order)) != len(order):
            raise ActionFailed(f"order must list distinct joint indices 0..{n - 1}, got {order}")
        full = q_now.copy()
        full[order] = targets[order]
        return full, [[j] for j in order]


@registry.register
class MoveJoints(JointMove):
    """Moves all arm joints together to ``targets`` or to a named arm ``state`` (e.g. tuck).

    - RUNNING while the arm moves (joints are timed to arrive together);
    - SUCCESS when every joint is within ``tolerance`` of its target;
    - FAILURE on an unknown state, targets outside the limits, a time-out, or a collision.
    Halted: the arm holds where it is.
    """

    INPUT_PORTS: ClassVar[dict[str, PortInformation]] = {
        **JointMove.INPUT_PORTS,
        "targets": PortInformation(list[float], False, "joint targets (or use state)", []),
        "state": PortInformation(str, False, "named arm state of the robot descriptor", ""),
    }

    def plan(self, q_now: np.ndarray) -> tuple[np.ndarray, list[list[int]]]:
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
        return targets, [list(range(len(q_now)))]


@registry.register
class Lift(JointMove):
    """Lifts by changing joints by ``deltas`` from where they are, one joint at a time.

    Scenario A's lift is ``deltas="0;-50;-30;0;0;0"`` (deg): joint 1 up by 50 deg, then joint 2
    by 30 deg. ``order`` picks the sequence (default: joints with a non-zero delta, in index
    order).

    - RUNNING while moving; SUCCESS when every changed joint is within ``tolerance``;
    - FAILURE when a new target is outside the limits, on a time-out, or on a collision.
    Halted: the arm holds where it is.
    """

    INPUT_PORTS: ClassVar[dict[str, PortInformation]] = {
        **JointMove.INPUT_PORTS,
        "deltas": PortInformation(list[float], True, "change of each arm joint"),
        "order": PortInformation(list[int], False, "joints in the order to move them", []),
    }

    def plan(self, q_now: np.ndarray) -> tuple[np.ndarray, list[list[int]]]:
        deltas = to_radians(self.get_input("deltas"), self.get_input("units"))
        n = len(q_now)
        if len(deltas) != n:
            raise ActionFailed(f"deltas has {len(deltas)} values; the arm has {n} joints")
        order = list(self.get_input("order")) or [j for j in range(n) if deltas[j] != 0.0]
        if any(not 0 <= j < n for j in order):
            raise ActionFailed(f"order must list joint indices 0..{n - 1}, got {order}")
        return q_now + deltas, [[j] for j in order]
