"""Path following for holonomic bases (omni-wheel, mecanum: planar x, y and yaw at once).

A holonomic base need not face where it goes: :class:`HolonomicFollower` pursues a look-ahead
point on the planned path with a planar velocity (vx, vy) while it turns to the goal heading
on the way, so a goal straight to the left of the robot is reached by driving sideways, without
turning. Like :class:`~bt_manip.navigation.controller.PathFollower` it never blocks and never
touches the simulator: :meth:`HolonomicFollower.update` takes the base pose and the time and
returns a :class:`HolonomicStatus` whose :attr:`~HolonomicStatus.velocity` (vx, vy, w in the
base frame) is applied with ``robot.set_base_velocity(*status.velocity)``.

Phases, as reported in ``phase`` while RUNNING:

- ``drive``: toward the point further along the path by a look-ahead that grows with the speed
  (from 0.12 m at rest up to ``lookahead``), but never past the next corner (a turn of the
  path by more than 0.35 rad) before the base is there, and the goal itself once the look-ahead
  reaches past the path's end. The speed is capped by ``max_speed``, by the braking distance to
  the goal and by the corners ahead: where the path turns by an angle a the base must be down
  to ``max_speed`` x cos(a) (0.08 m/s for a right angle or sharper), so it keeps to the path
  there and the planner's clearance holds. The yaw rate turns the base to the goal heading
  (capped by ``max_yaw_rate`` and by the braking angle). The planar velocity changes by at most
  ``max_accel`` x dt per tick (as a vector), the yaw rate by ``max_yaw_accel`` x dt.
- ``settle``: within 0.9 ``xy_tolerance`` and half ``yaw_tolerance`` of the goal at the path's
  end, the command ramps to zero and stays there for ``settle_time`` seconds.

It answers SUCCEEDED when, after settling, the base is within ``xy_tolerance`` and
``yaw_tolerance`` of the goal (otherwise it drives again). It answers FAILED:

- ``stuck`` when the distance left (path, plus 0.3 m per radian of heading error) has not
  shrunk by ``stuck_distance`` for ``stuck_time`` seconds (a wall or a heavy object stops the
  base's bounded motors); SUCCEEDED instead when the base stopped within the tolerances;
- ``could not settle on the goal`` after ``max_final_attempts`` settles that ended outside the
  tolerances;
- with the re-planner's reason when the path became blocked and no new path exists.

After SUCCEEDED or FAILED the command is zero.

The planner plans a holonomic base as a disc of the footprint's turning radius
(:func:`turning_footprint`): it may turn anywhere along the path, so the whole path keeps the
room the footprint sweeps when it turns.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from bt_manip.navigation.controller import (
    FollowerOptions,
    FollowState,
    FollowStatus,
    PathProgress,
    Pose2D,
    wrap,
)
from bt_manip.navigation.footprint import PlanarFootprint
from bt_manip.navigation.shapes import Disc

__all__ = [
    "HolonomicFollower",
    "HolonomicStatus",
    "base_limited",
    "turning_footprint",
]

POSITION_GAIN = 1.5
"""1/s: near the goal the speed is at most this times the distance left."""
MIN_SPEED = 0.03
"""m/s: the speed is not cut below this while the goal is further than half the tolerance."""
BRAKE_SHARE = 0.8
"""Share of the acceleration limit the braking profile plans with (the rest absorbs a tick's
delay)."""
CORNER_SPEED = 0.08
"""m/s: the speed a right-angle (or sharper) corner of the path is taken at."""
LOOK_BASE = 0.12
"""m: the look-ahead distance at rest; it grows by half the speed (in m per m/s)."""
CORNER_BRAKE_SHARE = 0.5
"""Share of the acceleration limit the base slows down with for a corner (the rest turns its
velocity toward the look-ahead point as it nears the corner)."""
CORNER_STEP = 0.1
"""m: a corner closer than half this is where the base already is (the look-ahead passes it)."""
CORNER_COS = math.cos(0.35)
"""A turn of the path by more than 0.35 rad is a corner: the look-ahead point stops there."""


@dataclass(frozen=True)
class HolonomicStatus(FollowStatus):
    """A :class:`FollowStatus` with the holonomic command.

    ``cmd`` holds (vx, w) for callers that only drive a forward speed and a yaw rate.
    """

    velocity: tuple[float, float, float] = (0.0, 0.0, 0.0)
    """(vx, vy, w): forward and leftward speed (m/s, base frame) and yaw rate (rad/s)."""


def turning_footprint(footprint: PlanarFootprint) -> PlanarFootprint:
    """The disc a holonomic base plans with: the footprint's turning radius around its origin."""
    return PlanarFootprint((Disc(0.0, 0.0, footprint.circumradius),), footprint.label)


def base_limited(options: FollowerOptions, base: Any) -> FollowerOptions:
    """``options`` with speeds and accelerations capped by a holonomic base's descriptor."""
    return dataclasses.replace(
        options,
        max_speed=min(options.max_speed, base.max_speed),
        max_yaw_rate=min(options.max_yaw_rate, base.max_yaw_rate),
        max_accel=min(options.max_accel, base.max_accel),
        max_yaw_accel=min(options.max_yaw_accel, base.max_yaw_accel),
        pivot=0.0,
    )


class HolonomicFollower(PathProgress):
    """Follows ``path`` (n, 2) of the base frame to ``goal`` (x, y, yaw), or (x, y) to keep the
    heading, driving sideways as needed; see the module docstring."""

    def __init__(
        self,
        path: np.ndarray,
        goal: tuple[float, ...],
        options: FollowerOptions | None = None,
        *,
        path_blocked: Callable[[np.ndarray], bool] | None = None,
        replan: Callable[[Pose2D], np.ndarray | str] | None = None,
    ) -> None:
        self.options = options or FollowerOptions()
        self.goal_xy = (float(goal[0]), float(goal[1]))
        self.goal_yaw: float | None = float(goal[2]) if len(goal) > 2 else None
        self.path_blocked = path_blocked
        self.replan = replan
        self.replans = 0
        self._set_path(np.asarray(path, dtype=float))
        self._vel = (0.0, 0.0)  # world frame
        self._w = 0.0
        self._last_time: float | None = None
        self._tick = 0.05
        self._last_check: float | None = None
        self._phase = "drive"
        self._settle_start = 0.0
        self._settles = 0
        self._best = math.inf
        self._best_time: float | None = None
        self._done: HolonomicStatus | None = None

    def _set_path(self, path: np.ndarray) -> None:
        seg = self._take_path(path)
        path = self.path
        with np.errstate(invalid="ignore", divide="ignore"):
            dirs = np.diff(path, axis=0) / seg[:, None]
        self._dirs = np.where(seg[:, None] > 1e-9, dirs, np.nan)
        """Unit direction of each segment (NaN for a segment of no length)."""
        self._index = 0
        self._best = math.inf

    # -- one tick -----------------------------------------------------------------------------
    def update(self, pose: Pose2D, now: float) -> HolonomicStatus:
        """Advance one tick from base pose ``pose`` (x, y, yaw) at time ``now`` (s)."""
        if self._done is not None:
            return self._done
        o = self.options
        dt = 0.0 if self._last_time is None else max(0.0, now - self._last_time)
        if dt > 0.0:
            self._tick = dt
        self._last_time = now
        if self._best_time is None:
            self._best_time = now
        x, y, yaw = pose
        failure = self._maybe_replan(pose, now)
        if failure is not None:
            return self._finish(FollowState.FAILED, failure)
        self._advance(x, y)
        gx, gy = self.goal_xy
        d_goal = math.hypot(gx - x, gy - y)
        yaw_err = 0.0 if self.goal_yaw is None else wrap(self.goal_yaw - yaw)
        within = d_goal <= o.xy_tolerance and abs(yaw_err) <= o.yaw_tolerance
        at_end = self.remaining() <= o.xy_tolerance

        if self._phase == "settle":
            stopped = self._vel == (0.0, 0.0) and self._w == 0.0
            if now - self._settle_start < o.settle_time or not stopped:
                return self._command(0.0, 0.0, 0.0, dt, yaw)
            if within:
                return self._finish(FollowState.SUCCEEDED, "goal reached")
            self._phase = "drive"
            self._best = math.inf
            if self._settles >= o.max_final_attempts:
                return self._finish(
                    FollowState.FAILED,
                    f"could not settle on the goal: {d_goal:.2f} m and {abs(yaw_err):.2f} rad "
                    f"off after {o.max_final_attempts} attempts",
                )
        elif at_end and d_goal <= 0.9 * o.xy_tolerance and abs(yaw_err) <= 0.5 * o.yaw_tolerance:
            self._phase = "settle"
            self._settle_start = now
            self._settles += 1
            return self._command(0.0, 0.0, 0.0, dt, yaw)

        vx, vy = self._pursue(x, y, d_goal)
        w = self._turn(yaw_err)
        px, py = self.path[self._index]
        progress = self.remaining() + math.hypot(px - x, py - y) + 0.3 * abs(yaw_err)
        if progress < self._best - o.stuck_distance:
            self._best = progress
            self._best_time = now
        elif now - self._best_time > o.stuck_time:
            if within:
                return self._finish(FollowState.SUCCEEDED, "goal reached")
            return self._finish(
                FollowState.FAILED,
                f"stuck: no progress for {o.stuck_time:.1f} s, {d_goal:.2f} m and "
                f"{abs(yaw_err):.2f} rad from the goal",
            )
        return self._command(vx, vy, w, dt, yaw)

    # -- parts ---------------------------------------------------------------------------------
    def _pursue(self, x: float, y: float, d_goal: float) -> tuple[float, float]:
        """World velocity toward the look-ahead point, braking for the goal."""
        o = self.options
        speed_now = math.hypot(*self._vel)
        look = min(o.lookahead, LOOK_BASE + 0.5 * speed_now)
        corner = self._next_corner(look)
        if corner is not None:
            look = corner  # drive to the corner, then along the next stretch
        if self.remaining() <= look:
            tx, ty = self.goal_xy
        else:
            tx, ty = self._lookahead_point(look)
        dist = math.hypot(tx - x, ty - y)
        if dist < 1e-6:
            return 0.0, 0.0
        left = max(self.remaining(), d_goal)
        v = min(o.max_speed, math.sqrt(2.0 * BRAKE_SHARE * o.max_accel * left))
        v = min(v, self._corner_speed(), max(POSITION_GAIN * d_goal, MIN_SPEED))
        if d_goal <= 0.5 * o.xy_tolerance and self.remaining() <= look:
            v = min(v, POSITION_GAIN * d_goal)
        return v * (tx - x) / dist, v * (ty - y) / dist

    def _turns_ahead(self, reach: float) -> tuple[np.ndarray, np.ndarray]:
        """For each path segment starting within ``reach`` m ahead of the progress point: how
        far ahead it starts (m) and the cosine of its turn from the segment that leads to the
        progress point (the base may not have passed that point yet)."""
        k0 = self._index
        start = max(k0 - 1, 0)
        end = int(np.searchsorted(self._s, self._s[k0] + reach, side="right"))
        dirs = self._dirs[start : min(end, len(self._dirs))]
        valid = np.flatnonzero(np.isfinite(dirs[:, 0]))
        if len(valid) < 2:
            return np.zeros(0), np.zeros(0)
        here = dirs[valid[0]]
        ahead = self._s[start + valid[1:]] - self._s[k0]
        return ahead, dirs[valid[1:]] @ here

    def _corner_speed(self) -> float:
        """The highest speed from which the base can slow down for every corner ahead: where
        the path turns by an angle a it must be down to ``max_speed`` x cos(a), at least
        :data:`CORNER_SPEED`."""
        o = self.options
        brake = CORNER_BRAKE_SHARE * o.max_accel
        ahead, cos_turn = self._turns_ahead(o.max_speed**2 / (2.0 * brake) + o.lookahead)
        if len(ahead) == 0:
            return o.max_speed
        at_corner = np.maximum(CORNER_SPEED, o.max_speed * cos_turn)
        return float(min(o.max_speed, np.min(np.sqrt(at_corner**2 + 2.0 * brake * ahead))))

    def _next_corner(self, within: float) -> float | None:
        """Distance along the path to the first corner (a turn of more than 0.35 rad) within
        ``within`` metres, unless the base is already at it."""
        ahead, cos_turn = self._turns_ahead(within)
        sharp = np.flatnonzero(cos_turn < CORNER_COS)
        if len(sharp) == 0:
            return None
        distance = float(ahead[sharp[0]])
        return distance if distance > CORNER_STEP / 2.0 else None

    def _turn(self, error: float) -> float:
        """Yaw rate toward the goal heading, braking for it."""
        o = self.options
        if abs(error) <= 1e-9:
            return 0.0
        rate = min(
            o.max_yaw_rate,
            o.heading_gain * abs(error),
            math.sqrt(2.0 * BRAKE_SHARE * o.max_yaw_accel * abs(error)),
        )
        return math.copysign(rate, error)

    def _command(self, vx: float, vy: float, w: float, dt: float, yaw: float) -> HolonomicStatus:
        """Limit the change of the world velocity and the yaw rate; the base-frame command."""
        o = self.options
        dvx, dvy = vx - self._vel[0], vy - self._vel[1]
        step = math.hypot(dvx, dvy)
        most = o.max_accel * dt
        if step > most:
            dvx, dvy = dvx * most / step, dvy * most / step
        vel = (self._vel[0] + dvx, self._vel[1] + dvy)
        speed = math.hypot(*vel)
        if speed > o.max_speed:
            vel = (vel[0] * o.max_speed / speed, vel[1] * o.max_speed / speed)
        if speed < 1e-9 and vx == 0.0 and vy == 0.0:
            vel = (0.0, 0.0)
        dw = max(-o.max_yaw_accel * dt, min(o.max_yaw_accel * dt, w - self._w))
        self._w = max(-o.max_yaw_rate, min(o.max_yaw_rate, self._w + dw))
        if abs(self._w) < 1e-9 and w == 0.0:
            self._w = 0.0
        self._vel = vel
        # the base turns during the coming tick: aim the world velocity from its mid-tick heading
        heading = yaw + 0.5 * self._w * self._tick
        c, s = math.cos(heading), math.sin(heading)
        bx, by = c * vel[0] + s * vel[1], -s * vel[0] + c * vel[1]
        return HolonomicStatus(
            FollowState.RUNNING, "", (bx, self._w), self._phase, (bx, by, self._w)
        )

    def _finish(self, state: FollowState, reason: str) -> HolonomicStatus:
        self._vel = (0.0, 0.0)
        self._w = 0.0
        self._done = HolonomicStatus(state, reason, (0.0, 0.0), self._phase)
        return self._done

    def _lookahead_point(self, distance: float) -> tuple[float, float]:
        """The path point ``distance`` ahead of the progress point (the end at most)."""
        target = self._s[self._index] + distance
        k = int(np.searchsorted(self._s, target))
        if k >= len(self.path):
            return float(self.path[-1, 0]), float(self.path[-1, 1])
        if k == 0:
            return float(self.path[0, 0]), float(self.path[0, 1])
        s0, s1 = self._s[k - 1], self._s[k]
        t = 0.0 if s1 <= s0 else (target - s0) / (s1 - s0)
        p = self.path[k - 1] + t * (self.path[k] - self.path[k - 1])
        return float(p[0]), float(p[1])
