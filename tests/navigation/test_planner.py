"""Grid planning in the world: shortcuts, footprints, and the reasons when there is no path."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from bt_manip.navigation.costmap import CostMap, InflationOptions
from bt_manip.navigation.footprint import PlanarFootprint
from bt_manip.navigation.grid import OccupancyGrid
from bt_manip.navigation.planner import PlanOutcome, plan_path
from bt_manip.navigation.smoothing import densify, path_length, segment_max_cost, shortcut


def two_rooms(gap: float) -> CostMap:
    """8 m x 4 m, a wall at x = 4 m with a doorway ``gap`` wide centred at y = 2 m."""
    grid = OccupancyGrid.empty((0.0, 0.0, 8.0, 4.0), 0.05)
    occ = grid.occupied
    occ[:, :2] = occ[:, -2:] = occ[:2, :] = occ[-2:, :] = True
    occ[:, 79:81] = True
    half = round(gap / 0.05 / 2)
    occ[40 - half : 40 + half, 79:81] = False
    return CostMap(grid, InflationOptions(margin=0.05))


def test_path_through_a_doorway_keeps_clear_and_is_smooth() -> None:
    cm = two_rooms(1.0)
    fp = PlanarFootprint.rectangle(0.9, 0.6)
    plan = plan_path(cm, fp, (1.0, 0.8), (7.0, 3.2))
    assert plan.ok, plan.reason
    assert np.allclose(plan.polyline[0], (1.0, 0.8)) and np.allclose(plan.polyline[-1], (7.0, 3.2))
    # every point of the path keeps the footprint's half width + margin from walls
    clear = [cm.clearance_at(x, y) for x, y in plan.polyline]
    assert min(clear) >= fp.half_width + 0.05 - 1e-9
    assert np.hypot(*np.diff(plan.polyline, axis=0).T).max() <= 0.05 + 1e-9
    assert plan.length == pytest.approx(path_length(plan.polyline))
    assert plan.length < 1.15 * np.hypot(6.0, 2.4)


def test_too_wide_a_footprint_gets_the_footprint_reason() -> None:
    cm = two_rooms(1.0)
    wide = PlanarFootprint.rectangle(0.9, 1.2, label="robot + panel")
    plan = plan_path(cm, wide, (1.0, 2.0), (7.0, 2.0))
    assert plan.outcome is PlanOutcome.FOOTPRINT
    assert "robot + panel" in plan.reason and "narrower robot" in plan.reason


def test_other_reasons() -> None:
    cm = two_rooms(1.0)
    fp = PlanarFootprint.circle(0.3)
    assert plan_path(cm, fp, (1.0, 2.0), (4.0, 0.5)).outcome is PlanOutcome.GOAL_IN_OBSTACLE
    assert plan_path(cm, fp, (1.0, 2.0), (9.0, 2.0)).outcome is PlanOutcome.GOAL_OUTSIDE
    near = plan_path(cm, fp, (1.0, 2.0), (3.8, 1.0))  # 0.15 m from the wall: too close
    assert near.outcome is PlanOutcome.FOOTPRINT and "too close" in near.reason
    closed = two_rooms(0.0)
    assert plan_path(closed, fp, (1.0, 2.0), (7.0, 2.0)).outcome is PlanOutcome.NO_PATH


def test_start_in_the_blocked_band_escapes_to_free_space() -> None:
    cm = two_rooms(1.0)
    fp = PlanarFootprint.circle(0.3)
    plan = plan_path(cm, fp, (0.3, 2.0), (2.0, 2.0))  # 0.2 m from the west wall
    assert plan.ok and np.allclose(plan.polyline[0], (0.3, 2.0))


def test_shortcut_never_crosses_blocked_cells() -> None:
    rng = np.random.default_rng(5)
    from bt_manip.navigation.astar import plan as astar_plan

    done = 0
    while done < 40:
        cost = rng.uniform(1.0, 3.0, (40, 40)).astype(np.float32)
        cost[rng.random((40, 40)) < 0.25] = np.inf
        free = np.argwhere(np.isfinite(cost))
        a, b = free[rng.choice(len(free), 2, replace=False)]
        path = astar_plan(cost, tuple(a), tuple(b))
        if path is None:
            continue
        corners = shortcut(cost, path)
        assert tuple(corners[0]) == tuple(a) and tuple(corners[-1]) == tuple(b)
        for p, q in itertools.pairwise(corners):
            assert np.isfinite(segment_max_cost(cost, p[0], p[1], q[0], q[1]))
        done += 1


def test_diagonal_segment_between_two_blocked_corners_is_blocked() -> None:
    cost = np.ones((3, 3), np.float32)
    cost[0, 1] = cost[1, 0] = np.inf
    assert segment_max_cost(cost, 0, 0, 1, 1) == np.inf
    assert segment_max_cost(cost, 1, 1, 2, 2) == 1.0


def test_densify() -> None:
    pts = densify(np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 0.33]]), 0.1)
    assert np.allclose(pts[0], (0, 0)) and np.allclose(pts[-1], (1.0, 0.33))
    assert np.hypot(*np.diff(pts, axis=0).T).max() <= 0.1 + 1e-12
    assert path_length(pts) == pytest.approx(1.33)
