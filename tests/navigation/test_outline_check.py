"""The grouped footprint check answers exactly as the point-by-point check, on any grid."""

from __future__ import annotations

import math

import numpy as np
import pytest

from bt_manip.navigation.distance import squared_distances
from bt_manip.navigation.footprint import PlanarFootprint
from bt_manip.navigation.lattice import outline_samples
from bt_manip.navigation.outline_check import (
    WindowMinima,
    _groups_free,
    _points_free,
    point_groups,
    window_cells,
)

RES = 0.05
ORIGIN = (-1.3, 0.7)


def both_answers(
    clear: np.ndarray, pts: np.ndarray, poses: np.ndarray, need: float, window: int | None = None
) -> tuple[list[bool], list[bool]]:
    """Per pose, the point-by-point answer and the grouped one (``window``: the windows' side,
    the right one by default)."""
    groups = point_groups(pts)
    side = window_cells(groups, RES) if window is None else window
    minima = WindowMinima(clear.shape, side)
    x0, y0 = ORIGIN
    slow, fast = [], []
    for x, y, th in poses:
        slow.append(bool(_points_free(clear, x0, y0, RES, pts, x, y, th, need)))
        fast.append(
            bool(
                _groups_free(
                    clear, x0, y0, RES, groups.points, groups.first, groups.centre,
                    groups.radius, groups.reach, minima.low, minima.done, minima.window,
                    x, y, math.cos(th), math.sin(th), need,
                )
            )
        )
    return slow, fast


def random_poses(rng: np.random.Generator, shape: tuple[int, int], n: int) -> np.ndarray:
    """Poses over the whole grid and a little beyond its edges, any heading."""
    rows, cols = shape
    x0, y0 = ORIGIN
    return np.column_stack(
        [
            rng.uniform(x0 - 0.3, x0 + cols * RES + 0.3, n),
            rng.uniform(y0 - 0.3, y0 + rows * RES + 0.3, n),
            rng.uniform(-4.0, 4.0, n),
        ]
    )


def obstacle_grid(rng: np.random.Generator, shape: tuple[int, int]) -> np.ndarray:
    """Squared cell distances of a grid with walls and scattered obstacles."""
    occ = rng.random(shape) < 0.0005
    occ[0, :] = occ[-1, :] = occ[:, 0] = occ[:, -1] = True
    occ[shape[0] // 2, : shape[1] // 2] = True
    d2 = squared_distances(occ)
    assert d2 is not None
    return d2


def test_grouped_check_matches_the_point_check_on_clearance_grids() -> None:
    rng = np.random.default_rng(3)
    d2 = obstacle_grid(rng, (100, 140))
    clear = np.sqrt(d2.astype(float)) * RES - RES / math.sqrt(2.0)
    fp = PlanarFootprint.rectangle(1.0, 0.4, x_offset=0.25)
    pts = outline_samples(fp)
    for grid in (clear, d2):  # float clearances and squared cell distances
        for need in (RES / math.sqrt(2.0), 0.05 + RES / math.sqrt(2.0), 0.2):
            slow, fast = both_answers(grid, pts, random_poses(rng, d2.shape, 1500), need)
            assert fast == slow
            assert 0.1 < np.mean(slow) < 0.9  # both answers are common


def test_grouped_check_matches_on_grids_without_structure() -> None:
    # any values, NaN and infinities included: the grouped check assumes nothing of the grid
    rng = np.random.default_rng(4)
    grid = rng.uniform(0.0, 1.0, (60, 60))
    grid[rng.random(grid.shape) < 0.02] = np.nan
    grid[rng.random(grid.shape) < 0.02] = np.inf
    grid[rng.random(grid.shape) < 0.02] = -np.inf
    pts = rng.uniform(-0.4, 0.4, (40, 2))
    for need in (0.01, 0.02, -1.0):
        slow, fast = both_answers(grid, pts, random_poses(rng, grid.shape, 3000), need)
        assert fast == slow
        assert any(slow)


def test_grouped_check_near_the_grid_edges() -> None:
    grid = np.full((40, 50), 2.0)
    pts = outline_samples(PlanarFootprint.rectangle(0.8, 0.4))
    # poses along the edges: some points just on the grid, some just off it
    xs = ORIGIN[0] + np.linspace(0.3, 0.5, 41)
    poses = np.array([(x, ORIGIN[1] + 1.0, th) for x in xs for th in (0.0, 0.7, math.pi / 2)])
    slow, fast = both_answers(grid, pts, poses, 0.1)
    assert fast == slow
    assert any(slow) and not all(slow)


def test_a_window_too_small_would_be_caught() -> None:
    # the comparison above has teeth: windows smaller than a group's box accept groups with
    # points on blocked cells
    rng = np.random.default_rng(5)
    d2 = obstacle_grid(rng, (70, 90))
    pts = outline_samples(PlanarFootprint.rectangle(1.4, 0.5, x_offset=0.35))
    slow, fast = both_answers(d2, pts, random_poses(rng, d2.shape, 1500), 0.1, window=1)
    assert fast != slow


@pytest.mark.parametrize("size", [0.05, 0.2, 1.0])
def test_groups_hold_every_point_once(size: float) -> None:
    pts = outline_samples(PlanarFootprint.rectangle(1.2, 0.6, x_offset=0.2))
    groups = point_groups(pts, size)
    assert groups.first[0] == 0 and groups.first[-1] == len(pts)
    assert sorted(map(tuple, groups.points)) == sorted(map(tuple, pts))
    for j in range(len(groups.radius)):
        members = groups.points[groups.first[j] : groups.first[j + 1]]
        assert len(members) > 0
        assert np.hypot(*(members - groups.centre[j]).T).max() < groups.radius[j]
        assert np.hypot(*groups.centre[j]) + groups.radius[j] < groups.reach
    empty = point_groups(np.zeros((0, 2)))
    assert len(empty.radius) == 0 and empty.first.tolist() == [0]
