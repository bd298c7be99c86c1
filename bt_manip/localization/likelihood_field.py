"""The likelihood-field sensor model: how well a scan fits the map from a given pose.

A :class:`LikelihoodField` holds, for every cell of an occupancy grid, the distance (m) from
its centre to the centre of the nearest occupied cell, capped at ``laser_likelihood_max_dist``
(worked out once per map with :func:`bt_manip.navigation.distance.squared_distances`), plus
the free cells (where a global localisation may put particles), as flat indices.

A beam that ends at ``(x, y)`` has the likelihood

    pz = z_hit * exp(-d^2 / (2 sigma_hit^2)) + z_rand / range_max

where ``d`` is the field's distance at ``(x, y)`` (``laser_likelihood_max_dist`` off the map).
A pose's log-likelihood is the sum of ``log pz`` over the beams used (the product of the beam
likelihoods). The ``z_rand`` floor bounds what one wrong beam (a person, a door left open) can
cost, and the filter tracks the geometric mean per beam (``exp(sum / beams)``) as the scan's
likelihood for recovery and the "lost" signal, a figure that does not depend on the number of
beams. (AMCL weighs a pose by ``1 + sum(pz^3)`` instead; that is flatter: a pose 10 cm off keeps
three quarters of the best weight, so the estimate stays wider.) Readings that are not finite,
not positive, or at or beyond ``range_max`` say nothing about where the wall is and are left
out.

:meth:`SensorModel.log_likelihoods` scores many poses at once: the beams' end points in the base
frame are worked out once per scan, moved into each particle's frame and looked up in a table of
``log pz`` per cell (one border cell around the grid stands for "off the map"), in a small
compiled loop (numba).
"""

from __future__ import annotations

from dataclasses import dataclass

import numba
import numpy as np

from bt_manip.localization.inputs import Scan
from bt_manip.navigation.distance import squared_distances
from bt_manip.navigation.grid import OccupancyGrid

MAX_FIELD_CELLS = 25_000_000
"""Largest map a field is built for (the occupancy grid's own bound)."""


@dataclass(frozen=True)
class LikelihoodField:
    """Distance to the nearest occupied cell per cell of a map, capped, with a border.

    ``distance`` has one extra cell on every side (value ``max_dist``): index it at
    ``(row + 1, col + 1)``.
    """

    origin: tuple[float, float]
    resolution: float
    distance: np.ndarray  # float32 (rows + 2, cols + 2)
    max_dist: float
    free: np.ndarray  # int32 or int64 (n,): flat indices (row * cols + col) of the free cells

    @classmethod
    def from_grid(cls, grid: OccupancyGrid, max_dist: float = 2.0) -> LikelihoodField:
        """The field of ``grid`` with distances capped at ``max_dist`` (m)."""
        if not max_dist > 0:
            raise ValueError(f"max_dist must be > 0, not {max_dist}")
        occ = np.asarray(grid.occupied, dtype=bool)
        if occ.size > MAX_FIELD_CELLS:
            raise ValueError(f"the map has {occ.size:,} cells, more than the "
                             f"{MAX_FIELD_CELLS:,} a likelihood field is built for")
        rows, cols = occ.shape
        dist = np.full((rows + 2, cols + 2), max_dist, np.float32)
        d2 = squared_distances(occ)
        if d2 is not None:
            inner = np.sqrt(d2.astype(np.float64)) * grid.resolution
            dist[1:-1, 1:-1] = np.minimum(inner, max_dist)
        free = np.flatnonzero(~occ).astype(np.int32 if occ.size < 2**31 else np.int64)
        dist.flags.writeable = False
        free.flags.writeable = False
        return cls(grid.origin, float(grid.resolution), dist, float(max_dist), free)

    @property
    def shape(self) -> tuple[int, int]:
        """(rows, cols) of the map (without the border)."""
        r, c = self.distance.shape
        return r - 2, c - 2

    def free_points(self, picks: np.ndarray) -> np.ndarray:
        """Centres (k, 2) of the free cells ``self.free[picks]``."""
        cols = self.shape[1]
        flat = self.free[picks].astype(np.int64)
        out = np.empty((flat.size, 2))
        out[:, 0] = self.origin[0] + (flat % cols + 0.5) * self.resolution
        out[:, 1] = self.origin[1] + (flat // cols + 0.5) * self.resolution
        return out

    def distance_at(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """The field's distance (m) at world points ``(x, y)`` (any matching shapes)."""
        out: np.ndarray = self.distance[self._index(np.asarray(x), np.asarray(y))]
        return out

    def _index(self, x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        rows, cols = self.shape
        inv = 1.0 / self.resolution
        col = np.floor((x - self.origin[0]) * inv)
        row = np.floor((y - self.origin[1]) * inv)
        # one border cell each side stands for everything off the map
        col = np.clip(col + 1.0, 0.0, cols + 1.0).astype(np.intp)
        row = np.clip(row + 1.0, 0.0, rows + 1.0).astype(np.intp)
        return row, col


class SensorModel:
    """Log-likelihoods of poses against one map for given ``z_hit``, ``z_rand``,
    ``sigma_hit``."""

    def __init__(
        self, field: LikelihoodField, z_hit: float, z_rand: float, sigma_hit: float
    ) -> None:
        self.field = field
        self.z_rand = float(z_rand)
        d = field.distance.astype(np.float64).ravel()
        self._gauss = z_hit * np.exp(-(d * d) / (2.0 * sigma_hit * sigma_hit))
        self._cols = field.distance.shape[1]
        self._log_tables: dict[float, np.ndarray] = {}

    def _log_table(self, range_max: float) -> np.ndarray:
        """``log(pz)`` per cell for scans of ``range_max`` (a few kept)."""
        table = self._log_tables.get(range_max)
        if table is None:
            pz = np.maximum(self._gauss + self.z_rand / range_max, 1e-30)  # log stays finite
            table = np.log(pz).astype(np.float32)
            if len(self._log_tables) >= 4:
                self._log_tables.clear()
            self._log_tables[range_max] = table
        return table

    def beam_ends(self, scan: Scan, max_beams: int) -> np.ndarray:
        """End points (m, 2) in the base frame of up to ``max_beams`` usable beams of
        ``scan``, evenly spaced among the usable ones (a scan whose returns are partly
        left out, by the robot's own body or a load across the laser, still gives the filter
        ``max_beams`` of them)."""
        r = scan.ranges
        usable = np.flatnonzero(np.isfinite(r) & (r > 0.0) & (r < scan.range_max))
        n = usable.size
        if n > max_beams:
            usable = usable[np.round(np.linspace(0.0, n - 1.0, max_beams)).astype(np.intp)]
        r = r[usable]
        a = scan.angles[usable]
        sx, sy, syaw = scan.sensor_pose
        return np.column_stack([sx + r * np.cos(syaw + a), sy + r * np.sin(syaw + a)])

    def log_likelihoods(
        self, poses: np.ndarray, ends: np.ndarray, range_max: float
    ) -> np.ndarray:
        """``sum(log pz)`` per pose (n, 3) over beam end points ``ends`` (m, 2) in the base
        frame (0 for every pose when there is no beam)."""
        rows, cols = self.field.shape
        out = np.zeros(poses.shape[0])
        if ends.shape[0]:
            _sum_logs(
                np.ascontiguousarray(poses, dtype=np.float64),
                np.ascontiguousarray(ends, dtype=np.float64),
                self._log_table(range_max), self.field.origin[0], self.field.origin[1],
                1.0 / self.field.resolution, rows, cols, out,
            )
        return out


@numba.njit(cache=True)
def _sum_logs(  # pragma: no cover - compiled
    poses: np.ndarray, ends: np.ndarray, table: np.ndarray, x0: float, y0: float, inv: float,
    rows: int, cols: int, out: np.ndarray,
) -> None:
    """Per pose, the sum over the beam ends of the table's value at the end, interpolated
    bilinearly between the four nearest cell centres (the border cells' value off the map);
    the table is the padded grid, flat."""
    stride = cols + 2
    hi_col, hi_row = cols + 0.0, rows + 0.0
    for i in range(poses.shape[0]):
        px, py = poses[i, 0], poses[i, 1]
        c, s = np.cos(poses[i, 2]), np.sin(poses[i, 2])
        total = 0.0
        for j in range(ends.shape[0]):
            bx, by = ends[j, 0], ends[j, 1]
            # position in padded cell-centre units: cell k's centre (padded index k) at k
            u = (px + c * bx - s * by - x0) * inv + 0.5
            v = (py + s * bx + c * by - y0) * inv + 0.5
            u = min(max(u, 0.0), hi_col)
            v = min(max(v, 0.0), hi_row)
            cu = np.floor(u)
            cv = np.floor(v)
            fu = u - cu
            fv = v - cv
            k = int(cv) * stride + int(cu)
            a = table[k] + fu * (table[k + 1] - table[k])
            b = table[k + stride] + fu * (table[k + stride + 1] - table[k + stride])
            total += a + fv * (b - a)
        out[i] = total
