"""Time along a planned joint path: when the arm is where, within its velocity and acceleration
limits.

A planned path is a list of joint configurations joined by straight segments, each checked
collision-free. :func:`time_parameterise` gives it a timing the arm can follow exactly: on each
segment every joint moves in proportion (so the arm keeps to the checked segment), speeding up
and slowing down along a trapezoidal velocity profile that keeps every joint within its
velocity limit and its acceleration limit, and the arm comes to rest at each waypoint where the
path turns (a corner cannot be taken at speed without leaving the segments, and a path off
its segments is a path nobody checked). Waypoints where the path runs on straight
(:data:`STRAIGHT_COS`) are passed at speed: the profile runs over the joined segments as one.

The result, a :class:`Trajectory`, answers the position and velocity at any time; the arm's
position controllers are then given the position a little ahead of now, one tick at a time.
"""

from __future__ import annotations

import bisect
import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

__all__ = ["STRAIGHT_COS", "Trajectory", "time_parameterise"]

STRAIGHT_COS = 1.0 - 1e-9
"""Two segments whose directions' cosine is above this (about 0.003 deg apart: the same line)
are followed as one."""


@dataclass(frozen=True)
class _Piece:
    """One stretch between two stops: from ``start`` along ``direction`` (unit length in joint
    space) for ``length``, over ``duration`` seconds, starting at ``t0``."""

    t0: float
    start: np.ndarray
    direction: np.ndarray
    length: float
    accel: float
    """Path acceleration (joint-space distance / s^2) while speeding up and slowing down."""
    cruise: float
    """Top path speed (joint-space distance / s)."""
    t_ramp: float
    duration: float

    def along(self, t: float) -> tuple[float, float]:
        """Distance covered and path speed ``t`` seconds into the piece."""
        t = min(max(t, 0.0), self.duration)
        a, v, tr = self.accel, self.cruise, self.t_ramp
        if t < tr:
            return 0.5 * a * t * t, a * t
        if t <= self.duration - tr:
            return 0.5 * a * tr * tr + v * (t - tr), v
        left = self.duration - t
        return self.length - 0.5 * a * left * left, a * left


@dataclass(frozen=True)
class Trajectory:
    """A timed joint path (see the module docstring)."""

    pieces: tuple[_Piece, ...]
    goal: np.ndarray

    @property
    def duration(self) -> float:
        if not self.pieces:
            return 0.0
        last = self.pieces[-1]
        return last.t0 + last.duration

    def _piece(self, t: float) -> _Piece | None:
        if not self.pieces:
            return None
        starts = [p.t0 for p in self.pieces]
        return self.pieces[max(0, bisect.bisect_right(starts, t) - 1)]

    def position(self, t: float) -> np.ndarray:
        """Joint positions ``t`` seconds after the start (the goal from the end on)."""
        piece = self._piece(t)
        if piece is None or t >= self.duration:
            return self.goal.copy()
        s, _ = piece.along(t - piece.t0)
        out: np.ndarray = piece.start + piece.direction * s
        return out

    def velocity(self, t: float) -> np.ndarray:
        """Joint velocities ``t`` seconds after the start (zero before and after)."""
        piece = self._piece(t)
        if piece is None or t < 0.0 or t >= self.duration:
            return np.zeros_like(self.goal)
        _, v = piece.along(t - piece.t0)
        out: np.ndarray = piece.direction * v
        return out


def _profile(length: float, direction: np.ndarray, vmax: np.ndarray, amax: np.ndarray
             ) -> tuple[float, float, float, float]:
    """The fastest rest-to-rest trapezoid over ``length`` along ``direction``: its path
    acceleration, top speed, ramp time and duration."""
    moving = np.abs(direction) > 1e-12
    speed = float(np.min(vmax[moving] / np.abs(direction[moving])))
    accel = float(np.min(amax[moving] / np.abs(direction[moving])))
    if speed * speed / accel >= length:  # no time at top speed: a triangle
        t_ramp = math.sqrt(length / accel)
        return accel, accel * t_ramp, t_ramp, 2.0 * t_ramp
    t_ramp = speed / accel
    return accel, speed, t_ramp, length / speed + t_ramp


def time_parameterise(
    path: Sequence[Sequence[float]] | np.ndarray,
    velocity_limits: Sequence[float],
    acceleration_limits: Sequence[float],
) -> Trajectory:
    """Time ``path`` (configurations, first = where the arm is) within the limits (rad/s,
    rad/s^2, one per joint, all > 0); see the module docstring."""
    q = np.asarray(path, dtype=float)
    if q.ndim != 2 or len(q) < 1:
        raise ValueError("a path is a list of at least one configuration")
    vmax = np.asarray(velocity_limits, dtype=float)
    amax = np.asarray(acceleration_limits, dtype=float)
    if vmax.shape != (q.shape[1],) or amax.shape != (q.shape[1],):
        raise ValueError("one velocity and one acceleration limit per joint")
    if np.any(vmax <= 0) or np.any(amax <= 0):
        raise ValueError("velocity and acceleration limits must be > 0")
    # the stops: the first and last configurations and every corner
    keep = [q[0]]
    for a, b in itertools.pairwise(q[1:]):
        d1, d2 = a - keep[-1], b - a
        n1, n2 = float(np.linalg.norm(d1)), float(np.linalg.norm(d2))
        if n1 < 1e-12:
            continue
        if n2 > 1e-12 and float(d1 @ d2) / (n1 * n2) > STRAIGHT_COS:
            continue  # on straight: no stop
        keep.append(a)
    if len(q) > 1:
        keep.append(q[-1])
    pieces: list[_Piece] = []
    t0 = 0.0
    for a, b in itertools.pairwise(keep):
        delta = b - a
        length = float(np.linalg.norm(delta))
        if length < 1e-12:
            continue
        direction = delta / length
        accel, cruise, t_ramp, duration = _profile(length, direction, vmax, amax)
        pieces.append(_Piece(t0, a.copy(), direction, length, accel, cruise, t_ramp, duration))
        t0 += duration
    return Trajectory(tuple(pieces), q[-1].copy())
