"""Nav2's costmap clearing: ClearEntireCostmap, ClearCostmapAroundRobot and
ClearCostmapExceptRegion.

The robot's map is its static grid (walls, furniture) with the movable objects drawn in where
they were last seen. Clearing forgets the drawn objects (all of them, those within a square
round the robot, or those outside it); the next plan draws them again where they are now.
bt-manip keeps one map per robot, so the local and global costmaps a tree names
(``service_name``) are the same map.

When the run localises, the robot has Nav2's two costmaps, fed by its laser
(:mod:`bt_manip.navigation.layered`), and the nodes act as Nav2's do: on the costmap their
``service_name`` names (``local_costmap/clear_entirely_local_costmap``: the local one only;
``.../clear_entirely_global_costmap``: the global one only; a name with neither word: both),
forgetting the laser's marks of its obstacle layer (all of them, those within the square round
the robot's believed position, or those outside it). The static layer (walls, furniture) is
never cleared. Each node answers SUCCESS at once (FAILURE only without a world or a mobile
base).
"""

from __future__ import annotations

from typing import ClassVar

import numpy as np
from py_trees.common import Status
from py_trees.ports import PortInformation

from bt_manip.behaviours.base import RobotAction
from bt_manip.behaviours.navigate import synced_navigator
from bt_manip.bt.ports import POSITIVE, Port
from bt_manip.bt.registry import registry
from bt_manip.nav2.actions import Nav2Action
from bt_manip.navigation.grid import OccupancyGrid
from bt_manip.navigation.navigator import Navigator

SERVICE_PORTS: dict[str, PortInformation] = {
    **RobotAction.INPUT_PORTS,
    "service_name": PortInformation(str, False, "Service name", ""),
    "server_timeout": PortInformation(float, False, "Server timeout (ms)", 50.0),
}


def clear_map(nav: Navigator, keep: np.ndarray | None = None) -> None:
    """Forget the objects drawn on ``nav``'s map, except in the cells where ``keep`` (a bool
    grid) is True."""
    grid = nav.costmap.grid
    if keep is None or not grid.sources:
        nav.costmap = nav.costmap.with_grid(nav.static)
        return
    flat_keep = keep.reshape(-1)
    occupied = nav.static.occupied.copy()
    flat = occupied.reshape(-1)
    sources = {}
    for body, idx in grid.sources.items():
        kept = idx[flat_keep[idx]]
        if kept.size:
            flat[kept] = True
            sources[body] = kept
    s = nav.static
    nav.costmap = nav.costmap.with_grid(OccupancyGrid(s.origin, s.resolution, occupied, s.band,
                                                      sources))


def square_round(nav: Navigator, x: float, y: float, half: float) -> np.ndarray:
    """The cells of ``nav``'s map within the square of half side ``half`` centred on (x, y)."""
    grid = nav.static
    rows, cols = grid.shape
    xs = grid.origin[0] + (np.arange(cols) + 0.5) * grid.resolution
    ys = grid.origin[1] + (np.arange(rows) + 0.5) * grid.resolution
    inside: np.ndarray = (np.abs(ys - y)[:, None] <= half) & (np.abs(xs - x)[None, :] <= half)
    return inside


class _Clear(Nav2Action):
    OUTPUT_PORTS: dict[str, PortInformation] = {}

    def _set_result(self, code: int, message: str) -> None:
        pass  # Nav2's clearing services report no result code

    def step(self) -> Status:
        return Status.SUCCESS


@registry.register
class ClearEntireCostmap(_Clear):
    """Forgets every object drawn on the robot's map (when localising: every laser mark of the
    costmap ``service_name`` names). SUCCESS."""

    INPUT_PORTS: dict[str, PortInformation] = SERVICE_PORTS

    def begin(self) -> None:
        nav = synced_navigator(self, self.base())
        if nav.layers is not None:
            nav.layers.clear(str(self.get_input("service_name") or ""))
            nav.refresh()
            return
        clear_map(nav)


def _square_ports(what: str) -> dict[str, PortInformation]:
    """The service ports and ``reset_distance``, the distance from the robot to ``what``."""
    return {
        **SERVICE_PORTS,
        "reset_distance": Port(float, False, f"Distance from the robot to {what} (m)", 1.0,
                               POSITIVE),
    }


class _ClearSquare(_Clear):
    """Clears on one side of the square of half side ``reset_distance`` round the robot:
    inside it (``INSIDE``), else outside."""

    INSIDE: ClassVar[bool] = True

    def begin(self) -> None:
        robot = self.base()
        nav = synced_navigator(self, robot)
        x, y, _ = self.believed_pose(robot)
        half = float(self.get_input("reset_distance"))
        if nav.layers is not None:
            square = nav.layers.global_layer.square(x, y, half)
            nav.layers.clear(str(self.get_input("service_name") or ""),
                             square if self.INSIDE else ~square)
            nav.refresh()
            return
        square = square_round(nav, x, y, half)
        clear_map(nav, keep=~square if self.INSIDE else square)


@registry.register
class ClearCostmapAroundRobot(_ClearSquare):
    """Forgets the objects drawn (when localising: the laser marks of the costmap
    ``service_name`` names) within ``reset_distance`` (half the side of a square) of the robot.
    SUCCESS."""

    INPUT_PORTS: dict[str, PortInformation] = _square_ports("clear")


@registry.register
class ClearCostmapExceptRegion(_ClearSquare):
    """Forgets the objects drawn (when localising: the laser marks of the costmap
    ``service_name`` names) farther than ``reset_distance`` (half the side of a square) from
    the robot, keeping those near it. SUCCESS."""

    INSIDE = False
    INPUT_PORTS: dict[str, PortInformation] = _square_ports("keep")
