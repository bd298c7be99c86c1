"""Which of a set of candidate points the arm reaches with the tool in a given orientation,
tilting the tool within a cone when it reaches none.

A node that picks a point in a region (a drop cell over a bin, say) hands :func:`first_reached`
its candidates, the one it was asked for first and the others in the order it prefers them;
each is checked by inverse kinematics on the run's solver for the tool frame (the solver that
:mod:`bt_manip.manipulation.cartesian` and the arm moves use, so a point found here is one those
moves reach), and, when the caller gives one, by a test of the configuration found (a
collision check). The search:

1. every candidate in order with the requested orientation; the first one reached wins;
2. when none is, the tool tilted by ``tilt_steps`` even steps up to ``max_tilt``, the smallest
   tilt first and, for each tilt, the candidates in order again. The tilt turns the tool about
   the horizontal line through the point across the direction to the arm's base: the wrist
   moves toward the robot and the tool axis leans away from it, as a hand reaching over the
   far edge of a box does, which brings a point beyond the top-down reach within the arm's
   reach.

When nothing within the cone is reached, :class:`UnreachableError` says so with the best IK
error met (the candidate and the tilt it was met at), or the solver's reason when no solve got
as far as an error (a point beyond reach is rejected before any attempt).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from bt_manip.kinematics import IKSolver
from bt_manip.manipulation.cartesian import arm_ik, to_arm_base
from bt_manip.manipulation.errors import ManipulationError
from bt_manip.run.context import RobotServices

__all__ = ["ReachOptions", "Reached", "UnreachableError", "first_reached", "tilted"]


class UnreachableError(ManipulationError):
    """No candidate point is reached within the tilt cone; the message says the best error."""


@dataclass(frozen=True)
class ReachOptions:
    """How far the search may turn the tool.

    Attributes:
        max_tilt: largest tilt of the tool from the requested orientation (rad); 0 for none.
        tilt_steps: how many even steps the tilts from ``max_tilt / tilt_steps`` to
            ``max_tilt`` take.
    """

    max_tilt: float = math.radians(25.0)
    tilt_steps: int = 5

    def __post_init__(self) -> None:
        if not 0.0 <= self.max_tilt <= math.pi / 2:
            raise ValueError(f"max_tilt must be in [0, pi/2] rad, got {self.max_tilt}")
        if self.tilt_steps < 1:
            raise ValueError(f"tilt_steps must be at least 1, got {self.tilt_steps}")

    def tilts(self) -> list[float]:
        """The tilts tried, smallest first: 0, then the steps up to ``max_tilt``."""
        if self.max_tilt <= 0.0:
            return [0.0]
        return [0.0] + [self.max_tilt * k / self.tilt_steps for k in range(1, self.tilt_steps + 1)]


@dataclass(frozen=True)
class Reached:
    """The candidate the arm reaches: its place in the list, the tool's rotation there (world
    frame, 3x3), the tilt applied (rad) and the joints IK found."""

    index: int
    rotation: np.ndarray
    tilt: float
    q: np.ndarray


def tilted(rotation: np.ndarray, point: np.ndarray, base: np.ndarray, angle: float) -> np.ndarray:
    """``rotation`` (world, 3x3) of a tool at ``point`` turned by ``angle`` (rad) about the
    horizontal axis through the point across the direction to ``base``, so that what is above
    the point moves toward the base (see the module docstring). A point straight above or
    below the base is tilted along the world x axis."""
    if angle == 0.0:
        return np.array(rotation, dtype=float)
    out = np.array([point[0] - base[0], point[1] - base[1], 0.0])
    length = float(np.linalg.norm(out))
    out = out / length if length > 1e-9 else np.array([1.0, 0.0, 0.0])
    axis = np.cross(out, [0.0, 0.0, 1.0])  # turning -z toward `out` about this axis
    k = np.array([[0.0, -axis[2], axis[1]], [axis[2], 0.0, -axis[0]], [-axis[1], axis[0], 0.0]])
    turn = np.eye(3) + math.sin(angle) * k + (1.0 - math.cos(angle)) * (k @ k)
    result: np.ndarray = turn @ np.asarray(rotation, dtype=float)
    return result


@dataclass
class _Best:
    """The smallest IK error met so far, and where."""

    position_error: float = math.inf
    rotation_error: float = math.inf
    index: int = -1
    tilt: float = 0.0
    reason: str = ""

    def offer(self, error: float, rotation_error: float, index: int, tilt: float,
              reason: str) -> None:
        if not self.reason:
            self.reason, self.index, self.tilt = reason, index, tilt
        if math.isfinite(error) and error < self.position_error:
            self.position_error, self.rotation_error = error, rotation_error
            self.index, self.tilt, self.reason = index, tilt, reason


def first_reached(
    services: RobotServices,
    tip: str,
    points: Sequence[np.ndarray],
    rotation: np.ndarray,
    seed: np.ndarray,
    options: ReachOptions,
    accept: Callable[[np.ndarray], str | None] | None = None,
    describe: Callable[[int], str] = lambda i: f"point {i}",
) -> Reached:
    """The first of ``points`` (world) the arm's ``tip`` reaches with the tool at
    ``rotation`` (world, 3x3), else tilted within the cone of ``options`` (see the module
    docstring). IK starts from ``seed`` (the arm's joints now) and makes its usual seeded
    restarts. ``accept`` may refuse a configuration IK found (returning why, e.g. what it
    collides with); a refused one counts as not reached. ``describe`` names a candidate by
    its place in ``points`` for the error. UnreachableError when nothing is reached."""
    if not points:
        raise UnreachableError("no candidate points to reach")
    solver = arm_ik(services, tip).full
    base = services.robot.link_transform(services.robot.description.arm.base_link)[:3, 3]
    best = _Best()
    refused = ""
    for tilt in options.tilts():
        for i, point in enumerate(points):
            turned = tilted(rotation, point, base, tilt)
            pose = np.eye(4)
            pose[:3, :3] = turned
            pose[:3, 3] = point
            q = _solve(solver, to_arm_base(services.robot, pose), seed, best, i, tilt)
            if q is None:
                continue
            why = accept(q) if accept is not None else None
            if why is None:
                return Reached(i, turned, tilt, q)
            refused = refused or f"{describe(i)} tilted {math.degrees(tilt):g} deg: {why}"
    cone = (f"with the tool within {math.degrees(options.max_tilt):g} deg of the requested "
            "orientation" if options.max_tilt > 0 else "with the requested orientation")
    if math.isfinite(best.position_error):
        where = (f"best IK error {1000.0 * best.position_error:.2f} mm / "
                 f"{math.degrees(best.rotation_error):.2f} deg at {describe(best.index)} "
                 f"tilted {math.degrees(best.tilt):g} deg")
    else:
        where = f"{describe(best.index)}: {best.reason}" if best.reason else "no IK solve ran"
    extra = f"; reached but refused: {refused}" if refused else ""
    raise UnreachableError(f"no candidate is reached {cone}: {where}{extra}")


def _solve(solver: IKSolver, pose_base: np.ndarray, seed: np.ndarray, best: _Best, index: int,
           tilt: float) -> np.ndarray | None:
    """IK's joints for ``pose_base`` (arm base frame) from ``seed``, or None, the error
    offered to ``best``."""
    q = solver.solve_q(pose_base, seed)
    if q is not None:
        return q
    result = solver.solve(pose_base, q_seed=seed)
    if result.success:
        return np.asarray(result.q, dtype=float)
    best.offer(result.position_error, result.rotation_error, index, tilt, result.reason or "")
    return None
