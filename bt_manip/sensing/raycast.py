"""The 2D ray caster of the simulated laser: beams from one point against segments and circles.

:func:`cast` returns, per beam, the distance to the first thing it meets (``inf`` for none).
Segments are edges of counter-clockwise convex polygons and count only from outside: an edge
is skipped when the origin is not strictly on its outer side, so a shape that holds the origin
(the inside of the laser's own housing) is never seen, as a real laser does not see it.
Circles likewise count only from outside.

Each segment and circle is tested only against the beams that point at it: its angular span
seen from the origin gives a range of beam indices, so the cost grows with what the beams
meet, not with beams times shapes. Compiled with numba (cached on disk).
"""

from __future__ import annotations

import math

import numba
import numpy as np

__all__ = ["cast", "polygon_segments"]

_EPS_U = 1e-12
"""Slack on the segment parameter, so that a beam through a shared corner meets an edge."""
_EPS_ANGLE = 1e-9
"""Slack (rad) on an angular span, so that a beam grazing an end is still tested."""


def polygon_segments(polygons: tuple[np.ndarray, ...] | list[np.ndarray]) -> np.ndarray:
    """The edges of counter-clockwise polygons as rows (ax, ay, bx, by)."""
    if not polygons:
        return np.zeros((0, 4))
    starts = np.concatenate(polygons)
    ends = np.concatenate([np.roll(p, -1, axis=0) for p in polygons])
    return np.ascontiguousarray(np.column_stack([starts, ends]), dtype=float)


def cast(
    ox: float,
    oy: float,
    heading: float,
    angle_min: float,
    increment: float,
    beams: int,
    segments: np.ndarray,
    circles: np.ndarray,
) -> np.ndarray:
    """Distances (``beams``,) from (ox, oy) along beam ``k`` at ``heading + angle_min + k *
    increment`` (rad, world frame) to the first segment (rows ax, ay, bx, by) or circle (rows
    cx, cy, r) it meets from outside; ``inf`` where it meets none."""
    angles = heading + angle_min + increment * np.arange(beams)
    out = np.full(beams, np.inf)
    _cast(float(ox), float(oy), float(heading + angle_min), float(increment), np.cos(angles),
          np.sin(angles), np.ascontiguousarray(segments, dtype=float).reshape(-1, 4),
          np.ascontiguousarray(circles, dtype=float).reshape(-1, 3), out)
    return out


@numba.njit(cache=True)
def _beam_span(lo: float, span: float, increment: float, beams: int,
               first: np.ndarray) -> int:  # pragma: no cover - compiled
    """Beam index ranges covering the angles [lo, lo + span] (measured from the first beam,
    any real ``lo``): up to two ranges (the span may wrap past a full turn), written as
    [start, stop) pairs into ``first``; their count."""
    two_pi = 2.0 * math.pi
    lo = lo - _EPS_ANGLE
    span = span + 2.0 * _EPS_ANGLE
    lo = lo - two_pi * math.floor(lo / two_pi)
    count = 0
    a = lo
    b = lo + span
    for _ in range(2):
        k0 = max(math.ceil(a / increment), 0)
        k1 = min(math.floor(b / increment), beams - 1)
        if k1 >= k0:
            first[2 * count] = k0
            first[2 * count + 1] = k1 + 1
            count += 1
        if b < two_pi:
            break
        a = 0.0
        b = b - two_pi
    return count


@numba.njit(cache=True)
def _cast(ox: float, oy: float, start: float, increment: float, cos_a: np.ndarray,
          sin_a: np.ndarray, segments: np.ndarray, circles: np.ndarray,
          out: np.ndarray) -> None:  # pragma: no cover - compiled
    beams = out.shape[0]
    ranges = np.zeros(4, dtype=np.int64)
    for i in range(segments.shape[0]):
        ax, ay = segments[i, 0], segments[i, 1]
        ex, ey = segments[i, 2] - ax, segments[i, 3] - ay
        wx, wy = ax - ox, ay - oy
        # the origin must lie strictly outside the edge: to its right (polygons turn left)
        if ex * (-wy) - ey * (-wx) >= 0.0:
            continue
        ta = math.atan2(wy, wx)
        tb = math.atan2(wy + ey, wx + ex)
        d = tb - ta
        if d > math.pi:
            d -= 2.0 * math.pi
        elif d < -math.pi:
            d += 2.0 * math.pi
        lo = ta if d >= 0.0 else tb
        n = _beam_span(lo - start, abs(d), increment, beams, ranges)
        for r in range(n):
            for k in range(ranges[2 * r], ranges[2 * r + 1]):
                dx, dy = cos_a[k], sin_a[k]
                denom = dx * ey - dy * ex
                if denom == 0.0:
                    continue
                t = (wx * ey - wy * ex) / denom
                u = (wx * dy - wy * dx) / denom
                if t > 0.0 and -_EPS_U <= u <= 1.0 + _EPS_U and t < out[k]:
                    out[k] = t
    for i in range(circles.shape[0]):
        cx, cy, radius = circles[i, 0] - ox, circles[i, 1] - oy, circles[i, 2]
        dist2 = cx * cx + cy * cy
        if dist2 <= radius * radius:
            continue
        half = math.asin(radius / math.sqrt(dist2))
        centre = math.atan2(cy, cx)
        n = _beam_span(centre - half - start, 2.0 * half, increment, beams, ranges)
        for r in range(n):
            for k in range(ranges[2 * r], ranges[2 * r + 1]):
                b = cos_a[k] * cx + sin_a[k] * cy
                disc = b * b - (dist2 - radius * radius)
                if disc < 0.0:
                    continue
                t = b - math.sqrt(disc)
                if t > 0.0 and t < out[k]:
                    out[k] = t
