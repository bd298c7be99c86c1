"""One robot's global and local costmaps, fed by its laser (Nav2's two ``costmap_2d``
instances).

:class:`RobotCostmaps` holds two obstacle layers on the static grid's frame, each with its own
marks (:mod:`bt_manip.navigation.layers`):

- the **global** one, which the planners read (with the static layer and inflation, through the
  :class:`~bt_manip.navigation.navigator.Navigator`), updated at ``global_update_frequency``
  (Nav2's default 1 Hz);
- the **local** one, a :class:`~bt_manip.navigation.rolling_window.RollingWindow` of 5 m round
  the robot, which the path followers' blocked-path checks read, updated at
  ``local_update_frequency`` (Nav2's default 5 Hz).

Each update takes the latest scan (Nav2's ``observation_persistence: 0``). Who scans is the
robot's localisation (:class:`~bt_manip.localization.runtime.Localizer`): it lays the scan in
the map frame from the believed pose and calls :meth:`RobotCostmaps.take` when :meth:`due`.

Nav2's clear services act on the costmap their ``service_name`` names (:meth:`layers_for`):
``local_costmap/clear_entirely_local_costmap`` on the local one only,
``global_costmap/clear_entirely_global_costmap`` on the global one only.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from bt_manip.navigation.grid import OccupancyGrid
from bt_manip.navigation.layers import ObstacleLayer, ObstacleLayerOptions
from bt_manip.navigation.rolling_window import RollingWindow, RollingWindowOptions

GLOBAL = "global"
LOCAL = "local"


@dataclass(frozen=True)
class CostmapOptions:
    """The obstacle layers' parameters, the local window's size and the update rates (Hz)."""

    obstacle: ObstacleLayerOptions = field(default_factory=ObstacleLayerOptions)
    local: RollingWindowOptions = field(default_factory=RollingWindowOptions)
    global_update_frequency: float = 1.0
    local_update_frequency: float = 5.0

    def __post_init__(self) -> None:
        for name in ("global_update_frequency", "local_update_frequency"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0.0):
                raise ValueError(f"{name} must be a number > 0 (Hz), got {value}")


@dataclass
class CostmapCounts:
    """What the report tells of one costmap: its updates, the clears asked of it and the
    marks they forgot, the most cells it held marked at once."""

    updates: int = 0
    clears: int = 0
    cleared_cells: int = 0
    peak_marked_cells: int = 0


class RobotCostmaps:
    """The global and local costmaps' obstacle layers of one robot (see the module
    docstring), on the frame of ``grid`` (the static grid's: same origin, resolution and
    shape)."""

    def __init__(self, grid: OccupancyGrid, options: CostmapOptions = CostmapOptions(),
                 start: float = 0.0) -> None:
        self.options = options
        self.global_layer = ObstacleLayer.like(grid, options.obstacle)
        self.local = RollingWindow.like(self.global_layer, options.local)
        self.counts = {GLOBAL: CostmapCounts(), LOCAL: CostmapCounts()}
        self._next = {GLOBAL: start, LOCAL: start}

    def layer(self, name: str) -> ObstacleLayer:
        """The obstacle layer of costmap ``name`` (:data:`GLOBAL` or :data:`LOCAL`)."""
        return self.global_layer if name == GLOBAL else self.local.layer

    def due(self, now: float) -> bool:
        """Whether either costmap takes a scan at sim time ``now``."""
        return any(now >= t - 1e-9 for t in self._next.values())

    def take(self, now: float, robot_xy: tuple[float, float],
             sensor: tuple[float, float, float], angles: np.ndarray, ranges: np.ndarray,
             returned: np.ndarray) -> list[str]:
        """Give the scan (laid in the map frame: ``sensor`` is the laser's believed x, y and
        heading) to the costmaps due now; the names of those whose marks changed."""
        changed = []
        rates = {GLOBAL: self.options.global_update_frequency,
                 LOCAL: self.options.local_update_frequency}
        for name, rate in rates.items():
            if now < self._next[name] - 1e-9:
                continue
            while self._next[name] <= now + 1e-9:
                self._next[name] += 1.0 / rate
            if name == GLOBAL:
                moved = self.global_layer.update(sensor, angles, ranges, returned)
            else:
                moved = self.local.update(robot_xy, sensor, angles, ranges, returned)
            counts = self.counts[name]
            counts.updates += 1
            counts.peak_marked_cells = max(counts.peak_marked_cells, self.layer(name).count)
            if moved:
                changed.append(name)
        return changed

    def layers_for(self, service_name: str) -> list[str]:
        """The costmaps a Nav2 clear service acts on: the local one when its name holds
        "local", the global one when it holds "global", both when it names neither."""
        text = service_name.lower()
        named = [n for n in (LOCAL, GLOBAL) if n in text]
        return named or [LOCAL, GLOBAL]

    def clear(self, service_name: str, where: np.ndarray | None = None) -> int:
        """Forget the marks of the costmaps ``service_name`` names (all of them, or where the
        bool grid ``where`` is True); the number of marks forgotten."""
        total = 0
        for name in self.layers_for(service_name):
            n = self.layer(name).clear(where)
            counts = self.counts[name]
            counts.clears += 1
            counts.cleared_cells += n
            total += n
        return total

    def report(self) -> dict[str, int]:
        """The run report's ``costmap`` object: per costmap, the cells marked at the end, the
        most marked at once, its updates, the clears asked of it and the marks they forgot."""
        out: dict[str, int] = {}
        for name in (GLOBAL, LOCAL):
            c = self.counts[name]
            out[f"{name}_marked_cells"] = self.layer(name).count
            out[f"{name}_peak_marked_cells"] = c.peak_marked_cells
            out[f"{name}_updates"] = c.updates
            out[f"{name}_clears"] = c.clears
            out[f"{name}_cleared_cells"] = c.cleared_cells
        return out
