"""Inflation of an occupancy grid into the cost grid the planner searches.

From the occupied cells, each cell gets its *clearance*: a lower bound on the distance (m)
from the cell's centre to any obstacle surface (Euclidean distance to the nearest occupied
cell's centre minus half that cell's diagonal). Then, for a footprint of half width ``w``:

- cells with clearance below ``w + margin`` are blocked (``inf``);
- cells just outside cost more, ``1 + gradient_cost x (1 - s / gradient_reach)^2`` where ``s``
  is the clearance left beyond ``w + margin``, fading to 1 at ``gradient_reach``. Paths then
  keep to the middle of doorways and corridors when that costs little extra length.

A :class:`CostMap` keeps the clearance of one occupancy grid and caches one cost grid per
footprint width.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy.ndimage import distance_transform_edt

from bt_manip.navigation.footprint import PlanarFootprint
from bt_manip.navigation.grid import OccupancyGrid


@dataclass(frozen=True)
class InflationOptions:
    """How the footprint and the cost gradient inflate obstacles."""

    margin: float = 0.08
    """Clearance (m) kept on top of the footprint's half width."""
    gradient_cost: float = 6.0
    """Extra cost per metre at the edge of the blocked band."""
    gradient_reach: float = 0.6
    """Distance (m) beyond the blocked band over which the extra cost fades out."""


def clearance(grid: OccupancyGrid) -> np.ndarray:
    """Per cell, a lower bound (m) on the distance from its centre to an obstacle surface.

    ``inf`` everywhere if nothing is occupied; negative in occupied cells.
    """
    occ = grid.occupied
    if not occ.any():
        return np.full(occ.shape, np.inf)
    dist = distance_transform_edt(~occ) * grid.resolution
    return dist - grid.resolution / math.sqrt(2.0)


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


@dataclass
class CostMap:
    """An occupancy grid with its clearance and cost grids per footprint."""

    grid: OccupancyGrid
    options: InflationOptions = InflationOptions()
    clear: np.ndarray = field(init=False, repr=False)
    _costs: dict[float, np.ndarray] = field(init=False, repr=False, default_factory=dict)

    def __post_init__(self) -> None:
        self.clear = clearance(self.grid)

    def cost_for(self, footprint: PlanarFootprint | float) -> np.ndarray:
        """The cost grid for a footprint (or a half width in m); do not modify it."""
        w = footprint if isinstance(footprint, float | int) else footprint.half_width
        key = round(float(w), 4)
        if key not in self._costs:
            self._costs[key] = inflate(self.clear, key, self.options)
        return self._costs[key]

    def clearance_at(self, x: float, y: float) -> float:
        """Clearance (m) at the cell containing (x, y); 0 outside the grid."""
        cell = self.grid.world_to_cell(x, y)
        if not self.grid.inside(cell):
            return 0.0
        return float(self.clear[cell])

    def with_grid(self, grid: OccupancyGrid) -> CostMap:
        """A cost map of another occupancy grid with the same options."""
        return CostMap(grid, self.options)
