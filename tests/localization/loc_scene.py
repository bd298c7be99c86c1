"""A synthetic room for the localisation tests: its walls as rectangles, the occupancy grid drawn
from them with bt-manip's grid code, an exact ray caster on their edges, a route, and noisy
odometry along it."""

from __future__ import annotations

import itertools
import math
from collections.abc import Iterator

import numpy as np

from bt_manip.localization import OdomPose, Scan
from bt_manip.navigation.grid import OccupancyGrid
from bt_manip.navigation.shapes import Polygon

RECTS = [
    (0.0, 0.0, 8.0, 0.1), (0.0, 4.9, 8.0, 5.0), (0.0, 0.0, 0.1, 5.0), (7.9, 0.0, 8.0, 5.0),
    (3.0, 0.1, 3.1, 2.5),  # a half wall from the south side
    (5.0, 3.0, 7.9, 3.1),  # a half wall from the east side
    (1.0, 3.5, 1.6, 4.2),  # a cupboard
    (6.2, 0.8, 6.8, 1.2),  # a box
    (4.2, 3.8, 4.5, 4.1),  # a pillar
]
"""(xmin, ymin, xmax, ymax) of each solid: an 8 m x 5 m room, nothing symmetric about it."""

ROUTE = [(1.0, 1.0), (2.2, 1.0), (2.2, 3.0), (4.0, 3.0), (4.0, 1.2), (5.5, 1.2), (5.5, 2.3),
         (7.0, 2.3)]
"""Waypoints through the room's free space (~9.5 m)."""

BEAMS = 180
RANGE_MAX = 8.0


def rect_polygon(r: tuple[float, float, float, float]) -> Polygon:
    x0, y0, x1, y1 = r
    return Polygon(np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1]]))


def room_grid(resolution: float = 0.05) -> OccupancyGrid:
    grid = OccupancyGrid.empty((-0.5, -0.5, 8.5, 5.5), resolution)
    grid.mark([rect_polygon(r) for r in RECTS])
    return grid


def segments() -> np.ndarray:
    """(s, 2, 2) edges of the solids."""
    out = []
    for r in RECTS:
        v = rect_polygon(r).vertices
        out += [(v[i], v[(i + 1) % 4]) for i in range(4)]
    return np.array(out)


def cast(pose: np.ndarray, angles: np.ndarray, segs: np.ndarray) -> np.ndarray:
    """Exact range from (x, y) along each world angle to the nearest edge (RANGE_MAX if none):
    ray p + t d meets edge a + u e where t = cross(a - p, e) / cross(d, e),
    u = cross(a - p, d) / cross(d, e)."""
    d = np.column_stack([np.cos(angles), np.sin(angles)])[:, None, :]
    a = segs[None, :, 0, :] - pose[None, None, :2]
    e = segs[None, :, 1, :] - segs[None, :, 0, :]
    den = d[..., 0] * e[..., 1] - d[..., 1] * e[..., 0]
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (a[..., 0] * e[..., 1] - a[..., 1] * e[..., 0]) / den
        u = (a[..., 0] * d[..., 1] - a[..., 1] * d[..., 0]) / den
    hit = (np.abs(den) > 1e-12) & (t > 1e-9) & (u >= 0) & (u <= 1)
    return np.minimum(np.where(hit, t, np.inf).min(axis=1), RANGE_MAX)


def scan_at(pose: np.ndarray, rng: np.random.Generator, segs: np.ndarray) -> Scan:
    """A full-turn scan from ``pose`` with 1 cm range noise; no return reads RANGE_MAX."""
    rel = -math.pi + np.arange(BEAMS) * (2 * math.pi / BEAMS)
    r = cast(pose, pose[2] + rel, segs)
    r = np.where(r < RANGE_MAX, r + 0.01 * rng.standard_normal(BEAMS), RANGE_MAX)
    return Scan(r, -math.pi, 2 * math.pi / BEAMS, RANGE_MAX)


def drive(route: list[tuple[float, float]], step: float = 0.125,
          turn_step: float = 0.15) -> np.ndarray:
    """True poses (k, 3) along ``route``: straight legs in steps, turns on the spot."""
    x, y = route[0]
    yaw = math.atan2(route[1][1] - y, route[1][0] - x)
    out = [(x, y, yaw)]
    for (ax, ay), (bx, by) in itertools.pairwise(route):
        goal = math.atan2(by - ay, bx - ax)
        turn = (goal - yaw + math.pi) % (2 * math.pi) - math.pi
        for _ in range(int(abs(turn) / turn_step)):
            yaw += math.copysign(turn_step, turn)
            out.append((x, y, yaw))
        yaw = goal
        n = max(1, round(math.hypot(bx - ax, by - ay) / step))
        out += [(ax + (bx - ax) * k / n, ay + (by - ay) * k / n, yaw) for k in range(1, n + 1)]
        x, y = bx, by
    return np.array(out)


def odometry(truth: np.ndarray, rng: np.random.Generator, noise: float = 0.05,
             unseen: int | None = None) -> np.ndarray:
    """Odometry poses: each step's travel and turn scaled by ``1 + noise N(0, 1)``, summed;
    the step to index ``unseen`` (a kidnap) is not seen at all."""
    odom = np.empty_like(truth)
    odom[0] = truth[0]
    for k in range(1, len(truth)):
        a, b = truth[k - 1], truth[k]
        if k == unseen:
            a = b
        c, s = math.cos(a[2]), math.sin(a[2])
        fx = c * (b[0] - a[0]) + s * (b[1] - a[1])
        fy = -s * (b[0] - a[0]) + c * (b[1] - a[1])
        dyaw = (b[2] - a[2] + math.pi) % (2 * math.pi) - math.pi
        g = 1.0 + noise * rng.standard_normal(2)
        fx, fy, dyaw = fx * g[0], fy * g[0], dyaw * g[1]
        o = odom[k - 1]
        c, s = math.cos(o[2]), math.sin(o[2])
        odom[k] = (o[0] + c * fx - s * fy, o[1] + s * fx + c * fy, o[2] + dyaw)
    return odom


def readings(truth: np.ndarray, odom: np.ndarray,
             rng: np.random.Generator) -> Iterator[tuple[int, OdomPose, Scan]]:
    """(index, odometry pose, scan) per step."""
    segs = segments()
    for k in range(len(truth)):
        yield k, OdomPose(*map(float, odom[k]), time=0.1 * k), scan_at(truth[k], rng, segs)


def pose_error(est: tuple[float, float, float] | np.ndarray, truth: np.ndarray) -> tuple[float,
                                                                                       float]:
    """(position error m, |yaw error| rad)."""
    dyaw = (est[2] - truth[2] + math.pi) % (2 * math.pi) - math.pi
    return math.hypot(est[0] - truth[0], est[1] - truth[1]), abs(dyaw)
