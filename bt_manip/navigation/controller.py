"""A path follower for skid-steer (differential) bases, stepped once per tree tick.

:class:`PathFollower` tracks a world polyline with pure pursuit and ends by turning to the goal
heading. It never blocks and never touches the simulator: each :meth:`PathFollower.update`
takes the base pose and the time, does a bounded amount of work and returns a
:class:`FollowStatus` with the twist ``(v, w)`` to apply (``robot.set_base_twist(v, w)``).

Phases, as reported in :attr:`FollowStatus.phase` while RUNNING:

- ``turn``: the path lies too far to the side (more than ``turn_in_place_angle``); the base
  turns on the spot toward the look-ahead point.
- ``drive``: pure pursuit toward the point ``lookahead`` metres further along the path (the
  path's last stretch is extended past its end); speed capped by ``max_speed``, by the
  yaw-rate limit on curves and by the braking distance to the end of the path.
- ``approach``: the end of the path was reached more than ``xy_tolerance`` from the goal (or
  the base drifted 1.5 ``xy_tolerance`` away while turning to the heading); the base turns
  toward the goal and drives straight to it (backwards if it is just behind). A goal near and
  to the side is not turned to: the base first backs straight up until the goal lies ahead
  (``sidestep_distance``; on the first such approach only, later ones turn toward it).
- ``align``: at the goal, the base turns on the spot to the goal heading.
- ``settle``: well inside the tolerances, the command is zero for ``settle_time`` seconds.

It answers SUCCEEDED when, after settling, the base is within ``xy_tolerance`` and
``yaw_tolerance`` of the goal (otherwise it aligns again). It answers FAILED:

- ``stuck`` when the remaining distance (plus heading error) has not shrunk by
  ``stuck_distance`` for ``stuck_time`` seconds (SUCCEEDED instead if the base stopped within
  the tolerances);
- ``could not settle on the goal`` after ``max_final_attempts`` changes between approach,
  align and settle;
- with the re-planner's reason when the path became blocked and no new path exists.

After SUCCEEDED or FAILED the command is zero.

A skid-steer base does not turn about its base frame: wheel scrub makes it pivot about a point
``pivot`` metres ahead of it (measured 0.11-0.16 m on the Husky with its arm in PyBullet). The
follower tracks the path with that pivot point, and in ``approach`` and ``align`` steers it to
where it must be for the base frame to end on the goal, so turning to the goal heading does
not push the base off the goal. The pivot moves with the load and the arm's posture (0.21-0.27
m holding the panel), so when following a pose plan (the carry), in ``approach`` and
``align`` the follower steers the pivot learnt while the base turned
(:attr:`PathFollower.turn_pivot`, a :class:`~bt_manip.navigation.pivot.PivotEstimate` that
the followers of one pose plan share; a follower made without one keeps ``pivot``):
with the descriptor's value the point it steers would circle the real pivot as the base turns,
and the base could circle its target. While driving it tracks ``path``, the path of the point
``pivot`` ahead, as planned.

Speed and yaw rate change at most by the acceleration limits between calls. When a
``path_blocked`` check is given, it is called every ``replan_period`` seconds with the part of
the path still ahead; if it answers True, ``replan(pose)`` is asked for a new polyline (or a
reason string when there is none).
"""

from __future__ import annotations

import bisect
import enum
import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from bt_manip.navigation.pivot import PivotEstimate

Pose2D = tuple[float, float, float]


class FollowState(enum.Enum):
    RUNNING = "running"
    SUCCEEDED = "succeeded"
    FAILED = "failed"


@dataclass(frozen=True)
class FollowStatus:
    """What the follower wants now: state, why (for FAILED), phase, and the twist (v, w)."""

    state: FollowState
    reason: str
    cmd: tuple[float, float]
    phase: str = ""

    @property
    def running(self) -> bool:
        return self.state is FollowState.RUNNING


@dataclass(frozen=True)
class FollowerOptions:
    """Limits and tolerances of :class:`PathFollower` (SI units)."""

    max_speed: float = 0.8
    max_yaw_rate: float = 1.6
    max_accel: float = 1.0
    max_yaw_accel: float = 4.0
    lookahead: float = 0.45
    min_lookahead: float = 0.25
    xy_tolerance: float = 0.10
    yaw_tolerance: float = 0.10
    turn_in_place_angle: float = 1.0
    """Heading error (rad) to the look-ahead point beyond which the base turns on the spot."""
    resume_angle: float = 0.25
    """Heading error (rad) below which a turn on the spot ends and driving resumes."""
    heading_gain: float = 2.5
    min_turn_rate: float = 0.3
    """Smallest yaw rate (rad/s) used when turning on the spot (overcomes wheel scrub)."""
    approach_speed: float = 0.25
    """Speed (m/s) of the straight final approach used when the path's end is missed."""
    reverse_distance: float = 0.4
    """In ``approach``, a goal closer than this (m) behind the base is reached backwards."""
    sidestep_distance: float = 0.3
    """In ``approach``, a target closer than this (m) that lies to the side (more than 0.5 rad
    off both ahead and behind) is not turned to on the spot: the base first backs straight up
    until the target lies within 0.5 rad ahead, then drives in, so a base near obstacles does
    not sweep round by up to 90 deg (and back in ``align``) to move a few centimetres
    sideways. Done on the first approach that finds the target there only: a base whose turns
    to the heading drift it off the goal again turns toward it as before, rather than backing
    up and driving in over and over."""
    align_yaw_rate: float = 1.0
    """Largest yaw rate (rad/s) when turning to the goal heading."""
    align_creep: float = 0.12
    """Largest speed (m/s) used to hold the pivot on its spot while turning to the heading."""
    pivot: float = 0.0
    """Where the base turns about when its wheels turn it on the spot (m ahead of the base
    frame; about 0.13 for the Husky carrying its arm)."""
    settle_time: float = 0.25
    """Time (s) the base stands still at the goal before success is declared."""
    max_final_attempts: int = 12
    """Phase changes (approach, align, settle) allowed before the goal is given up."""
    stuck_time: float = 4.0
    stuck_distance: float = 0.05
    replan_period: float = 1.0


def wrap(a: float) -> float:
    """Angle wrapped to [-pi, pi)."""
    return (a + math.pi) % (2.0 * math.pi) - math.pi


class PathProgress:
    """What the path followers share: progress along their path and replanning when it is
    blocked. A follower sets these attributes, and its ``_set_path`` sets ``path``, ``_s``
    (arc length at each point) and ``_index`` (the progress point)."""

    options: FollowerOptions
    path: np.ndarray
    _s: np.ndarray
    _s_list: list[float]
    _xs: np.ndarray
    _ys: np.ndarray
    _index: int
    _phase: str
    _last_check: float | None
    replans: int
    path_blocked: Callable[[np.ndarray], bool] | None
    replan: Callable[[Pose2D], np.ndarray | str] | None

    def _set_path(self, path: np.ndarray) -> None:
        raise NotImplementedError

    def _take_path(self, path: np.ndarray) -> np.ndarray:
        """Check ``path`` (n, 2), keep it (one point becomes a path of two) with its arc
        lengths ``_s``; returns the lengths of its stretches."""
        if path.ndim != 2 or path.shape[1] != 2 or len(path) == 0:
            raise ValueError("path must be an (n, 2) array with at least one point")
        if len(path) == 1:
            path = np.vstack([path, path])
        self.path = path
        seg: np.ndarray = np.hypot(*np.diff(path, axis=0).T)
        self._s = np.concatenate([[0.0], np.cumsum(seg)])
        self._s_list = self._s.tolist()  # the same lengths, searched without numpy per tick
        self._xs = np.ascontiguousarray(path[:, 0])
        self._ys = np.ascontiguousarray(path[:, 1])
        return seg

    @property
    def phase(self) -> str:
        return self._phase

    def remaining(self) -> float:
        """Path length (m) from the current progress point to the end."""
        return float(self._s[-1] - self._s[self._index])

    def _maybe_replan(self, pose: Pose2D, now: float) -> str | None:
        if self.path_blocked is None or self.replan is None:
            return None
        if self._last_check is not None and now - self._last_check < self.options.replan_period:
            return None
        self._last_check = now
        if not self.path_blocked(self.path[self._index :]):
            return None
        new = self.replan(pose)
        if isinstance(new, str):
            return f"path blocked and no new path: {new}"
        self.replans += 1
        self._set_path(np.asarray(new, dtype=float))
        self._phase = "drive"
        return None

    def _advance(self, x: float, y: float) -> None:
        """Move the progress index to the closest path point within a window ahead."""
        lo = self._index
        s = self._s_list
        hi = bisect.bisect_right(s, s[lo] + 1.5)
        hi = min(max(hi, lo + 2), len(s))
        d = np.hypot(self._xs[lo:hi] - x, self._ys[lo:hi] - y)
        self._index = lo + int(np.argmin(d))


class PathFollower(PathProgress):
    """Pure pursuit of the pivot point along ``path`` (n, 2), then a turn to the goal heading.

    ``goal`` is the base frame's goal, (x, y, yaw) or (x, y) for no final turn. ``path`` is
    the path of the pivot point (the navigator plans it from the pivot's start to where the
    pivot must end); with ``pivot`` 0 it is the path of the base frame itself. With
    ``reverse`` the base backs along the path.
    """

    def __init__(
        self,
        path: np.ndarray,
        goal: tuple[float, ...],
        options: FollowerOptions = FollowerOptions(),
        *,
        path_blocked: Callable[[np.ndarray], bool] | None = None,
        replan: Callable[[Pose2D], np.ndarray | str] | None = None,
        reverse: bool = False,
        pivot_estimate: PivotEstimate | None = None,
    ) -> None:
        self.options = options
        self.reverse = reverse
        self.goal_xy = (float(goal[0]), float(goal[1]))
        self.goal_yaw: float | None = float(goal[2]) if len(goal) > 2 else None
        self.path_blocked = path_blocked
        self.replan = replan
        self.replans = 0
        self.pivot_estimate = (
            pivot_estimate
            if pivot_estimate is not None
            else PivotEstimate(options.pivot, gain=0.0)
        )
        """Where the base turns about: ``options.pivot``, or learnt while turning when a
        learning estimate is given (the pose-plan follower gives one)."""
        self._set_path(np.asarray(path, dtype=float))
        self._cmd = (0.0, 0.0)
        self._last_time: float | None = None
        self._settle_start = 0.0
        self._switches = 0
        self._sidestepped = False
        self._sidestep_phase = False
        self._last_check: float | None = None
        self._phase = "drive"
        self._best = math.inf
        self._best_time: float | None = None
        self._done: FollowStatus | None = None

    def _set_path(self, path: np.ndarray) -> None:
        self._take_path(path)
        path = self.path
        self._index = 0
        self._best = math.inf
        # direction of the path's last stretch (from 0.2 m before the end)
        k = int(np.searchsorted(self._s, self._s[-1] - 0.2, side="right")) - 1
        d = path[-1] - path[max(0, min(k, len(path) - 2))]
        n = float(np.hypot(*d))
        self._end_dir = (float(d[0] / n), float(d[1] / n)) if n > 1e-9 else (1.0, 0.0)

    def follow(self, path: np.ndarray, goal: tuple[float, ...]) -> None:
        """Take over a new ``path`` (and ``goal``) from where the base is, keeping its speed:
        the tree replanned while the base drives."""
        self.goal_xy = (float(goal[0]), float(goal[1]))
        self.goal_yaw = float(goal[2]) if len(goal) > 2 else None
        self._set_path(np.asarray(path, dtype=float))
        self._best_time = self._last_time
        if self._phase in ("approach", "align") and self.remaining() > self.options.xy_tolerance:
            self._phase = "drive"

    @property
    def pivot(self) -> float:
        """The point (m ahead of the base frame) whose path ``path`` is, tracked while driving."""
        return self.options.pivot

    @property
    def turn_pivot(self) -> float:
        """Where the base turns about now (m ahead of its frame; learnt, see :mod:`.pivot`):
        the point steered onto its target in ``approach`` and held there in ``align``."""
        return self.pivot_estimate.value

    @property
    def path_end(self) -> tuple[float, float]:
        return float(self.path[-1, 0]), float(self.path[-1, 1])

    def pivot_point(self, pose: Pose2D, pivot: float | None = None) -> tuple[float, float]:
        """Where the point ``pivot`` m ahead (the path's :attr:`pivot` by default) is for base
        pose ``pose``."""
        p = self.pivot if pivot is None else pivot
        return pose[0] + p * math.cos(pose[2]), pose[1] + p * math.sin(pose[2])

    def pivot_target(self, yaw: float) -> tuple[float, float]:
        """Where the turning pivot (:attr:`turn_pivot`) must end (``yaw``: the heading when
        there is no goal heading)."""
        end_yaw = yaw if self.goal_yaw is None else self.goal_yaw
        return self.pivot_point((*self.goal_xy, end_yaw), self.turn_pivot)

    # -- one tick -----------------------------------------------------------------------------
    def update(self, pose: Pose2D, now: float) -> FollowStatus:
        """Advance one tick from base pose ``pose`` (x, y, yaw) at time ``now`` (s)."""
        if self._done is not None:
            return self._done
        o = self.options
        dt = 0.0 if self._last_time is None else max(0.0, now - self._last_time)
        self._last_time = now
        if self._best_time is None:
            self._best_time = now
        x, y, yaw = pose
        self.pivot_estimate.observe(pose, now)

        failure = self._maybe_replan(pose, now)
        if failure is not None:
            return self._finish(FollowState.FAILED, failure)

        # the path's point, the point the base turns about, and where that must end for the
        # base frame to end on the goal
        px, py = self.pivot_point(pose)
        qx, qy = self.pivot_point(pose, self.turn_pivot)
        tx, ty = self.pivot_target(yaw)
        d_pivot = math.hypot(tx - qx, ty - qy)
        self._advance(px, py)
        d_goal = math.hypot(self.goal_xy[0] - x, self.goal_xy[1] - y)
        yaw_err = 0.0 if self.goal_yaw is None else wrap(self.goal_yaw - yaw)
        to_end = self._to_end(px, py)
        at_end = to_end <= 0.5 * o.xy_tolerance
        if self._phase == "settle":
            if now - self._settle_start < o.settle_time or self._cmd != (0.0, 0.0):
                self._cmd = self._limit(0.0, 0.0, dt)
                return self._running()
            if d_goal <= o.xy_tolerance and abs(yaw_err) <= o.yaw_tolerance:
                return self._finish(FollowState.SUCCEEDED, "goal reached")
            self._phase = "align"
        elif (
            d_goal <= 0.9 * o.xy_tolerance
            and abs(yaw_err) <= 0.5 * o.yaw_tolerance
            and (at_end or self._phase in ("approach", "align"))
        ):
            self._phase = "settle"  # stop, let the base come to rest, then check again
            self._settle_start = now
            self._cmd = self._limit(0.0, 0.0, dt)
            return self._running()

        phase_before = self._phase
        if self._phase in ("drive", "turn") and at_end:
            self._phase = "align" if d_pivot <= 1.5 * o.xy_tolerance else "approach"
        if self._phase == "approach" and d_pivot <= 0.5 * o.xy_tolerance:
            self._phase = "align"
        if self._phase == "align" and (
            d_pivot > 1.5 * o.xy_tolerance
            or (abs(yaw_err) <= 0.5 * o.yaw_tolerance and d_goal > 0.9 * o.xy_tolerance)
        ):
            self._phase = "approach"  # drifted while turning, or turned but not on the spot
        if self._phase != phase_before and phase_before != "turn" and self._phase != "turn":
            self._best = math.inf  # a new phase measures progress afresh
            self._switches += 1
            if self._switches > o.max_final_attempts:
                return self._finish(
                    FollowState.FAILED,
                    f"could not settle on the goal: {d_goal:.2f} m and {abs(yaw_err):.2f} rad "
                    f"off after {o.max_final_attempts} attempts",
                )

        if self._phase == "align":
            # turn on the spot; creep along the heading to keep the pivot on its target
            ahead = (tx - qx) * math.cos(yaw) + (ty - qy) * math.sin(yaw)
            v_ref = max(-o.align_creep, min(o.align_creep, 2.0 * ahead))
            w_ref = max(-o.align_yaw_rate, min(o.align_yaw_rate, self._turn_rate(yaw_err)))
            progress = d_pivot + 0.3 * abs(yaw_err)
        elif self._phase == "approach":
            v_ref, w_ref, alpha = self._approach(qx, qy, yaw, tx, ty)
            progress = d_pivot + 0.3 * abs(alpha)
        else:
            v_ref, w_ref, alpha = self._pursue(px, py, yaw, to_end)
            progress = self.remaining() + 0.3 * abs(alpha)

        if progress < self._best - o.stuck_distance:
            self._best = progress
            self._best_time = now
        elif now - self._best_time > o.stuck_time:
            if d_goal <= o.xy_tolerance and abs(yaw_err) <= o.yaw_tolerance:
                return self._finish(FollowState.SUCCEEDED, "goal reached")
            return self._finish(
                FollowState.FAILED,
                f"stuck: no progress for {o.stuck_time:.1f} s, {d_goal:.2f} m from the goal",
            )
        self._cmd = self._limit(v_ref, w_ref, dt)
        return self._running()

    # -- parts ---------------------------------------------------------------------------------
    def _running(self) -> FollowStatus:
        """RUNNING with the command ``self._cmd`` (the pivot estimate is told it)."""
        self.pivot_estimate.sent(self._cmd)
        return FollowStatus(FollowState.RUNNING, "", self._cmd, self._phase)

    def _finish(self, state: FollowState, reason: str) -> FollowStatus:
        self._cmd = (0.0, 0.0)
        self.pivot_estimate.sent(self._cmd)
        self._done = FollowStatus(state, reason, (0.0, 0.0), self._phase)
        return self._done

    def _to_end(self, x: float, y: float) -> float:
        """Signed distance (m) left along the path; negative once past its end."""
        if self._s[-1] < 1e-9:
            return 0.0  # a path that is a single point
        if self._s[-1] - self._s[self._index] > 0.5:
            return self.remaining()
        ex, ey = self.path_end
        return (ex - x) * self._end_dir[0] + (ey - y) * self._end_dir[1]

    def _lookahead_point(self, distance: float) -> tuple[float, float]:
        """The path point ``distance`` ahead of the progress point; past the end, the path's
        last stretch is extended in a straight line."""
        s = self._s_list
        target = s[self._index] + distance
        k = bisect.bisect_left(s, target)
        if k >= len(s):
            extra = target - s[-1]
            ex, ey = self.path_end
            return ex + extra * self._end_dir[0], ey + extra * self._end_dir[1]
        if k == 0:
            return float(self.path[0, 0]), float(self.path[0, 1])
        s0, s1 = s[k - 1], s[k]
        t = 0.0 if s1 <= s0 else (target - s0) / (s1 - s0)
        ax, ay = float(self._xs[k - 1]), float(self._ys[k - 1])
        bx, by = float(self._xs[k]), float(self._ys[k])
        return ax + t * (bx - ax), ay + t * (by - ay)

    def _pursue(self, x: float, y: float, yaw: float, to_end: float) -> tuple[float, float, float]:
        """Pure pursuit along the path; returns (v, w, heading error)."""
        o = self.options
        look = min(o.lookahead, o.min_lookahead + 0.5 * abs(self._cmd[0]))
        lx, ly = self._lookahead_point(look)
        dist = math.hypot(lx - x, ly - y)
        if dist < 1e-6:
            return 0.0, 0.0, 0.0
        sign = -1.0 if self.reverse else 1.0
        if self.reverse:  # drive with the rear ahead: steer as if it were the front
            yaw = yaw + math.pi
        alpha = wrap(math.atan2(ly - y, lx - x) - yaw)
        if self._phase == "turn" and abs(alpha) < o.resume_angle:
            self._phase = "drive"
        elif self._phase == "drive" and abs(alpha) > o.turn_in_place_angle:
            self._phase = "turn"
        if self._phase == "turn":
            return 0.0, self._turn_rate(alpha), alpha
        curvature = 2.0 * math.sin(alpha) / dist
        v = o.max_speed
        if abs(curvature) > 1e-9:
            v = min(v, o.max_yaw_rate / abs(curvature))
        v = min(v, math.sqrt(o.max_accel * max(to_end, 0.0)) + 0.03)
        v *= max(0.0, math.cos(alpha))
        return sign * v, v * curvature, alpha

    def _approach(
        self, px: float, py: float, yaw: float, tx: float, ty: float
    ) -> tuple[float, float, float]:
        """Pivot straight to its target, backwards if that is just behind; (v, w, error)."""
        o = self.options
        dist = math.hypot(tx - px, ty - py)
        alpha = wrap(math.atan2(ty - py, tx - px) - yaw)
        sign = 1.0
        sideways = 0.5 < abs(alpha) < math.pi - 0.5
        if sideways and dist < o.sidestep_distance and self._sidestepping():
            # to the side and near: back straight up until it lies ahead, then drive in (a
            # goal pose near an object faces it: backing moves away from the object)
            return -min(o.approach_speed, 0.5 * o.approach_speed + dist), 0.0, alpha
        self._sidestep_phase = False
        if abs(alpha) > 0.5 * math.pi and dist < o.reverse_distance:
            sign = -1.0
            alpha = wrap(alpha - math.pi)
        if abs(alpha) > 0.5:
            return 0.0, self._turn_rate(alpha), alpha
        v = min(o.approach_speed, math.sqrt(o.max_accel * dist) + 0.02) * math.cos(alpha)
        w = self._turn_rate(alpha) if abs(alpha) > 0.05 else 0.0
        return sign * v, w, alpha

    def _sidestepping(self) -> bool:
        """Whether to back up from a goal to the side now: on the first approach that finds it
        there (and while that backing lasts), not again, so a base whose turns on the spot
        drift it off the goal does not back up and drive in over and over."""
        if self._sidestep_phase:
            return True
        if self._sidestepped:
            return False
        self._sidestepped = self._sidestep_phase = True
        return True

    def _turn_rate(self, error: float) -> float:
        o = self.options
        if abs(error) <= 1e-9:
            return 0.0
        w = math.copysign(max(abs(o.heading_gain * error), o.min_turn_rate), error)
        return max(-o.max_yaw_rate, min(o.max_yaw_rate, w))

    def _limit(self, v: float, w: float, dt: float) -> tuple[float, float]:
        o = self.options
        v0, w0 = self._cmd
        v = min(max(v, v0 - o.max_accel * dt), v0 + o.max_accel * dt)
        w = min(max(w, w0 - o.max_yaw_accel * dt), w0 + o.max_yaw_accel * dt)
        v = max(-o.max_speed, min(o.max_speed, v))
        w = max(-o.max_yaw_rate, min(o.max_yaw_rate, w))
        return v, w
