"""The costmap layers against cases worked out by hand: a box marked once a scan sees it, its
marks cleared when a later scan sees through it, a return with nothing behind clearing
nothing, the ranges, the believed pose's error carried into the marks, the rolling window, and
which costmap a clear service names."""

from __future__ import annotations

import math

import numpy as np
import pytest

from bt_manip.navigation.grid import OccupancyGrid
from bt_manip.navigation.layered import GLOBAL, LOCAL, CostmapOptions, RobotCostmaps
from bt_manip.navigation.layers import (
    ObstacleLayer,
    ObstacleLayerOptions,
    compose,
)
from bt_manip.navigation.rolling_window import RollingWindow, RollingWindowOptions

RES = 0.05
GRID = OccupancyGrid.empty((0.0, 0.0, 10.0, 10.0), RES)
BEAMS = 721
ANGLES = np.linspace(-math.pi, math.pi, BEAMS, endpoint=False)
RANGE_MAX = 12.0


def scan_of_walls(x: float, y: float, walls: list[float], half: float = 0.5) -> np.ndarray:
    """Ranges from (x, y), heading 0, to the nearest of the walls ``x = w`` (each ``2 half`` m
    long in y, centred on y); no return (RANGE_MAX) elsewhere."""
    r = np.full(BEAMS, RANGE_MAX)
    c = np.cos(ANGLES)
    for w in walls:
        with np.errstate(divide="ignore"):
            t = (w - x) / c
        hit_y = y + t * np.sin(ANGLES)
        ok = (t > 0) & (np.abs(hit_y - y) <= half)
        r = np.where(ok, np.minimum(r, t), r)
    return r


def cells_marked(layer: ObstacleLayer) -> set[tuple[int, int]]:
    return {(int(r), int(c)) for r, c in zip(*np.nonzero(layer.marked), strict=True)}


def update(layer: ObstacleLayer, ranges: np.ndarray, sensor: tuple[float, float, float]) -> bool:
    return layer.update(sensor, ANGLES, ranges, ranges < RANGE_MAX)


def test_a_box_is_marked_once_seen_and_cleared_when_seen_through() -> None:
    layer = ObstacleLayer.like(GRID)
    sensor = (1.0, 5.025, 0.0)
    # nothing within reach: a face 2.8 m ahead is beyond obstacle_max_range (2.5 m)
    assert not update(layer, scan_of_walls(1.0, 5.025, [3.8]), sensor)
    assert layer.count == 0
    # the box's face at x = 3.02 (2 m ahead): the column of cells x in [3.00, 3.05) it holds
    assert update(layer, scan_of_walls(1.0, 5.025, [3.02]), sensor)
    marked = cells_marked(layer)
    assert {c for _, c in marked} == {60}
    assert {r for r, _ in marked} == set(range(90, 111))  # y in [4.5, 5.55): |dy| <= 0.5
    v = layer.version
    # the box is gone and a wall stands 1 m behind it: the beams cross its cells, clearing them
    assert update(layer, scan_of_walls(1.0, 5.025, [4.0], half=2.0), sensor)
    assert layer.version == v + 1
    assert cells_marked(layer) == set()  # the new wall is 3 m away: not marked


def test_a_beam_with_no_return_clears_nothing() -> None:
    layer = ObstacleLayer.like(GRID)
    sensor = (1.0, 5.025, 0.0)
    update(layer, scan_of_walls(1.0, 5.025, [3.02]), sensor)
    before = cells_marked(layer)
    # the box is gone and nothing stands behind it: the marks stay (Nav2's inf_is_valid false)
    assert not update(layer, np.full(BEAMS, RANGE_MAX), sensor)
    assert cells_marked(layer) == before
    # a wall far behind clears along the beams up to raytrace_max_range only
    short = ObstacleLayer.like(GRID, ObstacleLayerOptions(raytrace_max_range=1.5))
    update(short, scan_of_walls(1.0, 5.025, [3.02]), sensor)
    update(short, scan_of_walls(1.0, 5.025, [9.0], half=4.0), sensor)
    assert cells_marked(short) == before


def test_marks_carry_the_believed_pose_error() -> None:
    truth, believed = ObstacleLayer.like(GRID), ObstacleLayer.like(GRID)
    ranges = scan_of_walls(1.0, 5.025, [3.02])
    update(truth, ranges, (1.0, 5.025, 0.0))
    update(believed, ranges, (1.2, 5.025, 0.0))  # the robot believes it is 0.2 m further on
    assert {c for _, c in cells_marked(believed)} == {64}  # 0.2 m = 4 cells further east
    assert len(cells_marked(believed)) == len(cells_marked(truth))


def test_compose_draws_the_marks_on_the_static_grid() -> None:
    static = OccupancyGrid.empty((0.0, 0.0, 10.0, 10.0), RES)
    static.occupied[0, :] = True
    layer = ObstacleLayer.like(static)
    assert compose(static, layer) is static
    update(layer, scan_of_walls(1.0, 5.025, [3.02]), (1.0, 5.025, 0.0))
    grid = compose(static, layer)
    assert grid.occupied[0].all() and grid.occupied[100, 60]
    assert not static.occupied[100, 60]
    with pytest.raises(ValueError, match="frame"):
        compose(OccupancyGrid.empty((0.0, 0.0, 5.0, 5.0), RES), layer)


def test_the_rolling_window_forgets_what_it_left_behind() -> None:
    window = RollingWindow.like(ObstacleLayer.like(GRID), RollingWindowOptions(width=5.0))
    ranges = scan_of_walls(1.0, 5.025, [3.02])
    window.update((1.0, 5.025), (1.0, 5.025, 0.0), ANGLES, ranges, ranges < RANGE_MAX)
    assert window.layer.count > 0
    path = np.array([[2.0, 5.0], [2.5, 5.0], [2.8, 5.0]])
    assert window.first_blocked(path, 0.6) == 1  # 0.525 m from the marks' centres
    assert window.first_blocked(path[:1], 0.6) is None
    window.move_to(6.0, 5.0)  # the face at x = 3.0 is 3 m behind: outside a 5 m window
    assert window.layer.count == 0
    # a 2 m window keeps none of a face 2 m ahead: its returns fall beyond the window's edge
    small = RollingWindow.like(ObstacleLayer.like(GRID), RollingWindowOptions(width=2.0))
    small.update((1.0, 5.025), (1.0, 5.025, 0.0), ANGLES, ranges, ranges < RANGE_MAX)
    assert small.layer.count == 0


def test_the_clear_services_act_on_the_costmap_they_name() -> None:
    maps = RobotCostmaps(GRID, CostmapOptions())
    ranges = scan_of_walls(1.0, 5.025, [3.02])
    assert maps.due(0.0)
    changed = maps.take(0.0, (1.0, 5.025), (1.0, 5.025, 0.0), ANGLES, ranges, ranges < RANGE_MAX)
    assert set(changed) == {GLOBAL, LOCAL}
    n = maps.global_layer.count
    assert n > 0 and maps.local.layer.count == n
    # local at 5 Hz, global at 1 Hz
    assert maps.due(0.2) and maps.take(0.2, (1.0, 5.025), (1.0, 5.025, 0.0), ANGLES, ranges,
                                       ranges < RANGE_MAX) == []
    assert maps.counts[LOCAL].updates == 2 and maps.counts[GLOBAL].updates == 1
    assert maps.layers_for("local_costmap/clear_entirely_local_costmap") == [LOCAL]
    assert maps.layers_for("global_costmap/clear_entirely_global_costmap") == [GLOBAL]
    assert maps.layers_for("") == [LOCAL, GLOBAL]
    assert maps.clear("local_costmap/clear_entirely_local_costmap") == n
    assert maps.local.layer.count == 0 and maps.global_layer.count == n
    # around the robot: a 1 m square round (1, 5) holds none of the face (2 m away)
    assert maps.clear("global_costmap/x", maps.global_layer.square(1.0, 5.0, 1.0)) == 0
    assert maps.clear("global_costmap/x", ~maps.global_layer.square(1.0, 5.0, 1.0)) == n
    report = maps.report()
    assert report["local_clears"] == 1 and report["global_clears"] == 2
    assert report["global_cleared_cells"] == n and report["global_peak_marked_cells"] == n
    assert report["global_marked_cells"] == 0


def test_options_are_checked() -> None:
    with pytest.raises(ValueError, match="obstacle_max_range"):
        ObstacleLayerOptions(obstacle_max_range=-1.0)
    with pytest.raises(ValueError, match="width"):
        RollingWindowOptions(width=0.0)
    with pytest.raises(ValueError, match="local_update_frequency"):
        CostmapOptions(local_update_frequency=math.inf)
