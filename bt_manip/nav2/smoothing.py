"""Nav2's SmoothPath, with a smoother of the kind of Nav2's simple smoother.

:func:`smooth_points` pulls each inner point of a polyline towards the middle of its
neighbours (weight ``w_smooth``) while a data term holds it near where it was planned
(``w_data``), sweep after sweep until the points move less than a tolerance or the sweeps
run out. The first and last points never move. A point that would move into a lethal cell of
the cost grid stays where it was, so a path that was free stays free.

SmoothPath smooths the pivot points of the base along a :class:`Nav2Path` (the line A* planned)
and rebuilds the base poses from them, the last pose being the goal as before.
"""

from __future__ import annotations

import dataclasses
import enum
from dataclasses import dataclass

import numpy as np
from py_trees.common import Status
from py_trees.ports import PortInformation

from bt_manip.behaviours.base import RobotAction
from bt_manip.behaviours.navigate import synced_navigator
from bt_manip.bt.node import PortError
from bt_manip.bt.ports import POSITIVE, Accepts, Port
from bt_manip.bt.registry import registry
from bt_manip.nav2.actions import Nav2Action, error_ports
from bt_manip.nav2.errors import SmootherError
from bt_manip.nav2.path import Nav2Path, path_from_points


@dataclass(frozen=True)
class SmootherOptions:
    """Nav2's simple smoother's defaults."""

    w_data: float = 0.2
    w_smooth: float = 0.3
    tolerance: float = 1e-10
    max_sweeps: int = 1000


class Smoothed(enum.Enum):
    CONVERGED = "converged"
    SWEEPS_USED = "sweeps used up"


def _lethal(cost: np.ndarray, origin: tuple[float, float], resolution: float,
            pts: np.ndarray) -> np.ndarray:
    """Per point (n, 2): whether it lies in a lethal cell or off the grid."""
    rows = np.floor((pts[:, 1] - origin[1]) / resolution).astype(np.int64)
    cols = np.floor((pts[:, 0] - origin[0]) / resolution).astype(np.int64)
    r, c = cost.shape
    inside = (rows >= 0) & (rows < r) & (cols >= 0) & (cols < c)
    out: np.ndarray = ~inside
    out[inside] = np.isinf(cost[rows[inside], cols[inside]])
    return out


def smooth_points(
    points: np.ndarray,
    cost: np.ndarray,
    origin: tuple[float, float],
    resolution: float,
    options: SmootherOptions = SmootherOptions(),
) -> tuple[np.ndarray, Smoothed]:
    """The smoothed polyline (n, 2) of ``points`` and whether the sweeps converged.

    Each sweep moves every inner point ``p`` by ``w_data * (original - p) + w_smooth *
    (previous + next - 2 p)`` (all points at once); points that would land in a lethal cell
    of ``cost`` (a grid with ``origin`` and ``resolution``) keep their place.
    """
    original = np.asarray(points, dtype=float)
    path = original.copy()
    if len(path) < 3:
        return path, Smoothed.CONVERGED
    for _ in range(options.max_sweeps):
        inner = path[1:-1]
        moved = inner + options.w_data * (original[1:-1] - inner) + options.w_smooth * (
            path[:-2] + path[2:] - 2.0 * inner)
        blocked = _lethal(cost, origin, resolution, moved)
        moved[blocked] = inner[blocked]
        change = float(np.sum(np.abs(moved - inner)))
        path[1:-1] = moved
        if change < options.tolerance:
            return path, Smoothed.CONVERGED
    return path, Smoothed.SWEEPS_USED


def first_lethal(cost: np.ndarray, origin: tuple[float, float], resolution: float,
                 points: np.ndarray) -> int | None:
    """Index of the first point of ``points`` in a lethal cell or off the grid, or None."""
    hits = _lethal(cost, origin, resolution, np.asarray(points, dtype=float))
    return int(np.argmax(hits)) if hits.any() else None


@registry.register
class SmoothPath(Nav2Action):
    """Smooths ``unsmoothed_path`` on the robot's costmap and writes it to ``smoothed_path``.

    Smoothing finishes within the tick (module docstring for the smoother); the path's first
    and last poses do not move.

    - SUCCESS: ``smoothed_path`` holds the new path, ``was_completed`` is true when the sweeps
      converged (false when they were used up first: the path is still smoother and free),
      ``smoothing_duration`` is 0 (no sim time passes), ``error_code_id`` 0;
    - FAILURE: 505 INVALID_PATH (no path, or an empty one), or with ``check_for_collisions``
      503 SMOOTHED_PATH_IN_COLLISION when the smoothed path crosses an obstacle of the costmap
      as it is now (``was_completed`` false); ``smoothed_path`` is left as it was.
    """

    UNKNOWN = SmootherError.UNKNOWN
    INPUT_PORTS: dict[str, PortInformation] = {
        **RobotAction.INPUT_PORTS,
        "unsmoothed_path": PortInformation(Nav2Path, True, "Path to be smoothed"),
        "max_smoothing_duration": Port(float, False, "Maximum smoothing duration (s)", 3.0,
                                       POSITIVE),
        "check_for_collisions": PortInformation(
            bool, False, "If true collision check will be performed after smoothing", False),
        "smoother_id": PortInformation(str, False, "Mapped name of the smoother plugin", ""),
        "server_name": PortInformation(str, False, "Action server name", ""),
        "server_timeout": Port(int, False, "Action server timeout (ms)", 20, Accepts(low=0)),
    }
    OUTPUT_PORTS: dict[str, PortInformation] = {
        "smoothed_path": PortInformation(Nav2Path, False, "Path smoothed by SmootherServer"),
        "smoothing_duration": PortInformation(float, False, "Time taken to smooth path (s)"),
        "was_completed": PortInformation(bool, False,
                                         "True if smoothing was not interrupted by time limit"),
        **error_ports("The smooth path"),
    }

    def _path(self) -> Nav2Path:
        try:
            path = self.get_input("unsmoothed_path", None)
        except PortError as exc:
            self.fail(SmootherError.INVALID_PATH, str(exc))
        if not isinstance(path, Nav2Path) or len(path) == 0:
            self.fail(SmootherError.INVALID_PATH, f"no path to smooth (got {path!r})")
        return path

    def begin(self) -> None:
        self.set_output("was_completed", False)
        path = self._path()
        robot = self.base()
        nav = synced_navigator(self, robot)
        nav.refresh()
        grid = nav.costmap.grid
        cost = nav.cost
        pivot = nav.pivot
        points = path.shifted(pivot)
        smoothed, outcome = smooth_points(points, cost, grid.origin, grid.resolution)
        if bool(self.get_input("check_for_collisions")):
            hit = first_lethal(cost, grid.origin, grid.resolution, smoothed)
            if hit is not None:
                x, y = smoothed[hit]
                self.fail(SmootherError.SMOOTHED_PATH_IN_COLLISION,
                          f"the smoothed path crosses an obstacle at ({x:.2f}, {y:.2f})")
        new = path_from_points(smoothed, path.goal, pivot)
        new = dataclasses.replace(new, frame_id=path.frame_id, planner_id=path.planner_id)
        new.poses[0] = path.poses[0]  # the start pose keeps its heading
        self.set_output("smoothed_path", new)
        self.set_output("smoothing_duration", 0.0)
        self.set_output("was_completed", outcome is Smoothed.CONVERGED)

    def step(self) -> Status:
        return Status.SUCCESS
