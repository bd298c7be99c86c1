"""Cartesian targets for the arm: IK on the robot's own model, straight-line paths.

Each robot gets one :class:`~bt_manip.kinematics.ArmModel` and solver per tip frame, built from
the same URDF PyBullet loaded and kept for the run by its
:class:`~bt_manip.run.context.RobotServices`. Solves are deterministic (no
wall-clock budget, a bounded number of seeded restarts), so the same run gives the same joints.
A target the arm cannot reach raises :class:`CartesianError` with IK's reason.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from bt_manip.kinematics import IKSolver, KinematicsError
from bt_manip.manipulation.errors import ManipulationError
from bt_manip.run.context import ArmIK, RobotServices

STEP = 0.02
"""Spacing (m) of the waypoints of a straight-line move."""
TURN_STEP = 0.1
"""Largest turn (rad) of the tool between two waypoints of a straight-line move."""


class CartesianError(ManipulationError):
    """The arm has no such chain, or no configuration reaches a pose; the message says why."""


def arm_ik(services: RobotServices, tip: str) -> ArmIK:
    """The run's model and solvers of the robot's arm from its base link to ``tip``."""
    try:
        return services.arm_ik(tip)
    except KinematicsError as exc:  # PyBullet loaded the URDF already: a bad tip name
        desc = services.robot.description
        raise CartesianError(f"no kinematic chain {desc.arm.base_link} -> {tip}: {exc}") from None


def to_arm_base(robot: Any, pose_world: np.ndarray) -> np.ndarray:
    """A world pose (4x4) expressed in the arm's base link frame."""
    pose_base: np.ndarray = _world_to_arm_base(robot) @ pose_world
    return pose_base


def _solver(services: RobotServices, tip: str, free_yaw: bool) -> IKSolver:
    """The IK solver for ``tip``: the one leaving the yaw about the tool axis free, or not."""
    ik = arm_ik(services, tip)
    return ik.free_yaw if free_yaw else ik.full


def _world_to_arm_base(robot: Any) -> np.ndarray:
    """The transform (4x4) taking world coordinates to the arm's base link frame."""
    base = robot.link_transform(robot.description.arm.base_link)
    inverse: np.ndarray = np.linalg.inv(base)
    return inverse


def solve(
    services: RobotServices,
    tip: str,
    pose_world: np.ndarray,
    seed: np.ndarray,
    free_yaw: bool = False,
) -> np.ndarray:
    """Joint values putting ``tip`` at ``pose_world``; CartesianError with IK's reason if none."""
    pose_base = _world_to_arm_base(services.robot) @ pose_world
    return _solved(_solver(services, tip, free_yaw), pose_base, pose_world, seed)


def _solved(
    solver: IKSolver, pose_base: np.ndarray, pose_world: np.ndarray, seed: np.ndarray
) -> np.ndarray:
    """The joints ``solver`` finds for ``pose_base`` (the arm base frame's ``pose_world``);
    CartesianError with IK's reason if none."""
    q = solver.solve_q(pose_base, seed)  # the usual case: the attempt from the seed succeeds
    if q is not None:
        return q
    result = solver.solve(pose_base, q_seed=seed)
    if not result.success:
        where = ", ".join(f"{v:.3f}" for v in pose_world[:3, 3])
        raise CartesianError(f"no arm configuration reaches ({where}): {result.reason}")
    return np.asarray(result.q, dtype=float)


def line(
    services: RobotServices,
    tip: str,
    start_world: np.ndarray,
    goal_world: np.ndarray,
    seed: np.ndarray,
    free_yaw: bool = False,
) -> list[np.ndarray]:
    """Joint waypoints moving ``tip`` on a straight line from ``start_world`` to
    ``goal_world``, one every :data:`STEP` metres (orientation turning evenly from the start's
    to the goal's), each seeded by the one before so the arm does not flip between
    solutions.

    The robot does not move while the line is planned, so the arm base frame and the turn
    between the two orientations are worked out once for all the waypoints."""
    a, b = start_world[:3, 3], goal_world[:3, 3]
    turning = _Turn(start_world[:3, :3], goal_world[:3, :3])
    n = max(1, int(np.ceil(max(float(np.linalg.norm(b - a)) / STEP, turning.angle / TURN_STEP))))
    solver = _solver(services, tip, free_yaw)
    to_base = _world_to_arm_base(services.robot)
    out = []
    q = seed
    (ax, ay, az), (dx, dy, dz) = a.tolist(), (b - a).tolist()
    for i in range(1, n + 1):
        s = i / n
        # the waypoint's pose, its position a + (b - a) s worked out on plain floats
        (r00, r01, r02), (r10, r11, r12), (r20, r21, r22) = turning.at(s).tolist()
        pose = np.array([
            [r00, r01, r02, ax + dx * s],
            [r10, r11, r12, ay + dy * s],
            [r20, r21, r22, az + dz * s],
            [0.0, 0.0, 0.0, 1.0],
        ])
        try:
            q = _solved(solver, to_base @ pose, pose, q)
        except CartesianError as exc:
            raise CartesianError(
                f"on the straight line from ({_xyz(a)}) to ({_xyz(b)}), waypoint {i} of {n} "
                f"({100.0 * s:.0f} % of the way): {exc}") from None
        out.append(q)
    return out


def _xyz(p: np.ndarray) -> str:
    return ", ".join(f"{v:.3f}" for v in p.tolist())


def _angle(ra: np.ndarray, rb: np.ndarray) -> float:
    return float(np.arccos(np.clip((np.trace(ra.T @ rb) - 1.0) / 2.0, -1.0, 1.0)))


class _Turn:
    """The rotations from ``ra`` to ``rb`` about one fixed axis; :meth:`at` gives the one a
    fraction ``s`` of the way. What does not depend on ``s`` (the relative rotation, its
    angle, the axis' cross-product matrix and its square) is worked out once."""

    def __init__(self, ra: np.ndarray, rb: np.ndarray) -> None:
        self.ra, self.rb = ra, rb
        rel = ra.T @ rb
        self.angle = angle = _angle(ra, rb)
        self.still = angle < 1e-9
        if self.still:
            return
        if np.pi - angle < 1e-6:  # half a turn: the axis is the eigenvector of eigenvalue 1
            w, v = np.linalg.eigh((rel + rel.T) / 2.0)
            axis = v[:, int(np.argmax(w))]
        else:
            axis = np.array([rel[2, 1] - rel[1, 2], rel[0, 2] - rel[2, 0], rel[1, 0] - rel[0, 1]])
            axis /= 2.0 * np.sin(angle)
        k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
        kk = k @ k
        self._k = k.ravel().tolist()
        self._kk = kk.ravel().tolist()

    def at(self, s: float) -> np.ndarray:
        """Rotation a fraction ``s`` of the way from ``ra`` to ``rb``: ``ra`` times
        ``I + sin(a) K + (1 - cos(a)) K^2`` for the angle ``a`` of that fraction."""
        if self.still:
            return self.rb.copy()
        a = self.angle * s
        sin_a = float(np.sin(a))
        vers_a = 1.0 - float(np.cos(a))
        # element by element, in numpy's order, zeros of I included (so that the signs of
        # zero results are the same too): (I + sin_a K) + vers_a K^2
        k, kk = self._k, self._kk
        step = np.array([
            [1.0 + sin_a * k[0] + vers_a * kk[0], 0.0 + sin_a * k[1] + vers_a * kk[1],
             0.0 + sin_a * k[2] + vers_a * kk[2]],
            [0.0 + sin_a * k[3] + vers_a * kk[3], 1.0 + sin_a * k[4] + vers_a * kk[4],
             0.0 + sin_a * k[5] + vers_a * kk[5]],
            [0.0 + sin_a * k[6] + vers_a * kk[6], 0.0 + sin_a * k[7] + vers_a * kk[7],
             1.0 + sin_a * k[8] + vers_a * kk[8]],
        ])
        turned: np.ndarray = self.ra @ step
        return turned

