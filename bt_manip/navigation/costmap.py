"""Inflation of an occupancy grid into the cost grid the planner searches.

From the occupied cells, each cell gets its *clearance*: a lower bound on the distance (m)
from the cell's centre to any obstacle surface (Euclidean distance to the nearest occupied
cell's centre minus half that cell's diagonal). Then, for a footprint of half width ``w``:

- cells with clearance below ``w + margin`` are blocked (``inf``);
- cells just outside cost more, ``1 + gradient_cost x (1 - s / gradient_reach)^2`` where ``s``
  is the clearance left beyond ``w + margin``, fading to 1 at ``gradient_reach``. Paths then
  keep to the middle of doorways and corridors when that costs little extra length.

A :class:`CostMap` keeps the squared cell distances of one occupancy grid
(:func:`bt_manip.navigation.distance.squared_distances`, 4 bytes per cell) and caches one
float32 cost grid per footprint width. A cell's cost depends only on its integer squared
distance, so a cost grid is read from a small table indexed by it (the table is
:func:`inflate` applied to the clearance of each squared distance: the same values, bit for
bit, as inflating a full clearance grid, without float64 temporaries the size of the grid).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numba
import numpy as np

from bt_manip.navigation.distance import squared_distances
from bt_manip.navigation.footprint import PlanarFootprint
from bt_manip.navigation.grid import OccupancyGrid

CHUNK_CELLS = 1 << 20
"""Cells converted per step when a full float64 clearance grid is asked for."""


@dataclass(frozen=True)
class InflationOptions:
    """How the footprint and the cost gradient inflate obstacles."""

    margin: float = 0.08
    """Clearance (m) kept on top of the footprint's half width."""
    gradient_cost: float = 6.0
    """Extra cost per metre at the edge of the blocked band."""
    gradient_reach: float = 0.6
    """Distance (m) beyond the blocked band over which the extra cost fades out."""


def clearance_of(d2: np.ndarray | None, shape: tuple[int, int], resolution: float) -> np.ndarray:
    """float64 clearance grid (m) from squared cell distances (``None``: nothing occupied)."""
    if d2 is None:
        return np.full(shape, np.inf)
    out = np.empty(d2.shape, np.float64)
    flat_in = d2.reshape(-1)
    flat = out.reshape(-1)
    half_diagonal = resolution / math.sqrt(2.0)
    for a in range(0, flat.size, CHUNK_CELLS):
        part = flat[a : a + CHUNK_CELLS]
        np.sqrt(flat_in[a : a + CHUNK_CELLS], out=part, dtype=np.float64)
        part *= resolution
        part -= half_diagonal
    return out


def clearance(grid: OccupancyGrid) -> np.ndarray:
    """Per cell, a lower bound (m) on the distance from its centre to an obstacle surface.

    ``inf`` everywhere if nothing is occupied; negative in occupied cells.
    """
    return clearance_of(squared_distances(grid.occupied), grid.shape, grid.resolution)


def inflate(
    clear: np.ndarray, half_width: float, options: InflationOptions = InflationOptions()
) -> np.ndarray:
    """float32 cost grid for a footprint of ``half_width`` from a clearance grid."""
    radius = half_width + options.margin
    spare = clear - radius
    cost = np.ones(clear.shape, np.float32)
    if options.gradient_cost > 0.0 and options.gradient_reach > 0.0:
        fade = np.clip(1.0 - spare / options.gradient_reach, 0.0, 1.0)
        cost += (options.gradient_cost * fade**2).astype(np.float32)
    cost[spare < 0.0] = np.inf
    return cost


def cost_table(
    resolution: float, half_width: float, options: InflationOptions, largest: int
) -> np.ndarray:
    """The cost of a cell by its squared distance ``d2`` (cells^2): entry ``min(d2, n - 1)``.

    The table stops at ``largest`` (the largest squared distance of the grid) or as soon as
    its last entry is 1: the cost never grows with the distance, so every farther cell costs 1.
    """
    n = 1024
    while True:
        size = min(n, largest + 1)
        d2 = np.arange(size, dtype=np.float64)
        table = inflate(np.sqrt(d2) * resolution - resolution / math.sqrt(2.0), half_width, options)
        if size == largest + 1 or table[-1] == 1.0:
            return table
        n *= 4


@numba.njit(cache=True)
def _look_up(d2: np.ndarray, table: np.ndarray, out: np.ndarray) -> None:
    last = table.shape[0] - 1
    for i in range(d2.shape[0]):
        k = d2[i]
        out[i] = table[k if k < last else last]


def cost_grid(
    d2: np.ndarray | None,
    shape: tuple[int, int],
    resolution: float,
    half_width: float,
    options: InflationOptions = InflationOptions(),
) -> np.ndarray:
    """float32 cost grid from squared cell distances; equal to ``inflate(clearance, ...)``."""
    if d2 is None:
        return np.full(shape, inflate(np.full(1, np.inf), half_width, options)[0], np.float32)
    table = cost_table(resolution, half_width, options, int(d2.max()))
    out = np.empty(d2.shape, np.float32)
    _look_up(d2.reshape(-1), table, out.reshape(-1))
    return out


@dataclass
class CostMap:
    """An occupancy grid with its squared cell distances and cost grids per footprint."""

    grid: OccupancyGrid
    options: InflationOptions = InflationOptions()
    d2: np.ndarray | None = field(init=False, repr=False)
    """Squared distance (cells^2) from each cell to the nearest occupied one (``None`` when
    nothing is occupied)."""
    _costs: dict[float, np.ndarray] = field(init=False, repr=False, default_factory=dict)

    def __post_init__(self) -> None:
        self.d2 = squared_distances(self.grid.occupied)

    def cost_for(self, footprint: PlanarFootprint | float) -> np.ndarray:
        """The cost grid for a footprint (or a half width in m); do not modify it."""
        w = footprint if isinstance(footprint, float | int) else footprint.half_width
        key = round(float(w), 4)
        if key not in self._costs:
            self._costs[key] = cost_grid(
                self.d2, self.grid.shape, self.grid.resolution, key, self.options
            )
        return self._costs[key]

    @property
    def clear(self) -> np.ndarray:
        """The float64 clearance grid (m), built anew on each call (8 bytes per cell): for a
        few cells, :meth:`clearance_of_cell` costs nothing."""
        return clearance_of(self.d2, self.grid.shape, self.grid.resolution)

    def clearance_of_cell(self, cell: tuple[int, int]) -> float:
        """Clearance (m) of a cell inside the grid (``inf`` when nothing is occupied)."""
        if self.d2 is None:
            return math.inf
        res = self.grid.resolution
        return math.sqrt(float(self.d2[cell])) * res - res / math.sqrt(2.0)

    def clearance_at(self, x: float, y: float) -> float:
        """Clearance (m) at the cell containing (x, y); 0 outside the grid."""
        cell = self.grid.world_to_cell(x, y)
        if not self.grid.inside(cell):
            return 0.0
        return self.clearance_of_cell(cell)

    def with_grid(self, grid: OccupancyGrid) -> CostMap:
        """A cost map of another occupancy grid with the same options."""
        return CostMap(grid, self.options)
