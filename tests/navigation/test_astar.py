"""Grid A*: cost-optimal against a Dijkstra oracle, valid paths, clear reasons for no path."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import dijkstra

from bt_manip.navigation import astar
from bt_manip.navigation.astar import PlanStatus, corner_cuts, path_cost, plan, plan_verbose

SIDES = [(-1, 0), (1, 0), (0, -1), (0, 1)]
DIAGONALS = [(-1, -1), (-1, 1), (1, -1), (1, 1)]


def oracle_cost(
    cost: np.ndarray, start: tuple[int, int], goal: tuple[int, int], diagonal: bool
) -> float:
    """Cheapest start-goal cost by scipy's Dijkstra on the same move graph."""
    rows, cols = cost.shape
    free = np.isfinite(cost)
    # pad with a blocked border so every cell has eight neighbours to look at
    fp = np.zeros((rows + 2, cols + 2), bool)
    fp[1:-1, 1:-1] = free
    ids = np.arange(rows * cols).reshape(rows, cols)
    src, dst, wts = [], [], []
    for dr, dc in SIDES + (DIAGONALS if diagonal else []):
        ok = free & fp[1 + dr : 1 + dr + rows, 1 + dc : 1 + dc + cols]
        if dr and dc:  # both cells beside a diagonal move must be free
            ok &= (
                fp[1 + dr : 1 + dr + rows, 1 : 1 + cols] & fp[1 : 1 + rows, 1 + dc : 1 + dc + cols]
            )
        r, c = np.nonzero(ok)
        src.append(ids[r, c])
        dst.append(ids[r + dr, c + dc])
        step = math.sqrt(2.0) if dr and dc else 1.0
        wts.append(step * cost[r + dr, c + dc].astype(np.float64))
    n = rows * cols
    graph = coo_matrix(
        (np.concatenate(wts), (np.concatenate(src), np.concatenate(dst))), shape=(n, n)
    ).tocsr()
    dist = dijkstra(graph, directed=True, indices=start[0] * cols + start[1])
    return float(dist[goal[0] * cols + goal[1]])


def random_case(rng: np.random.Generator) -> tuple[np.ndarray, tuple[int, int], tuple[int, int]]:
    rows, cols = (int(x) for x in rng.integers(2, 61, size=2))
    kind = int(rng.integers(5))
    if kind == 0:  # uniform cost: many equal-cost paths
        cost = np.ones((rows, cols), np.float32)
    elif kind == 1:  # small integer costs
        cost = rng.integers(1, 5, size=(rows, cols)).astype(np.float32)
    elif kind == 2:  # continuous costs
        cost = rng.uniform(1.0, 10.0, size=(rows, cols)).astype(np.float32)
    elif kind == 3:  # wide range (beyond the bucket search's ratio: the heap search runs)
        cost = np.exp(rng.uniform(0.0, 7.0, size=(rows, cols))).astype(np.float32)
    else:  # costs above 1 only, as an inflated occupancy grid has
        cost = (1.0 + rng.uniform(0.0, 1.0, size=(rows, cols)) ** 4 * 20.0).astype(np.float32)
    cost[rng.random((rows, cols)) < rng.uniform(0.0, 0.45)] = np.inf
    free = np.argwhere(np.isfinite(cost))
    if len(free) >= 2 and rng.random() < 0.9:
        a, b = free[rng.choice(len(free), size=2, replace=False)]
    else:
        a, b = rng.integers(0, [rows, cols]), rng.integers(0, [rows, cols])
    return cost, (int(a[0]), int(a[1])), (int(b[0]), int(b[1]))


def check_path(
    cost: np.ndarray,
    path: np.ndarray,
    start: tuple[int, int],
    goal: tuple[int, int],
    diagonal: bool,
) -> None:
    assert tuple(path[0]) == start and tuple(path[-1]) == goal
    assert np.isfinite(cost[path[:, 0], path[:, 1]]).all(), "path enters a blocked cell"
    steps = np.abs(np.diff(path, axis=0))
    assert (steps.max(axis=1) == 1).all(), "consecutive cells are not neighbours"
    if not diagonal:
        assert (steps.sum(axis=1) == 1).all(), "diagonal step in a 4-connected search"
    assert corner_cuts(cost, path) == 0


@pytest.mark.parametrize("force_heap", [False, True], ids=["buckets", "heap"])
def test_optimal_against_dijkstra_on_300_random_grids(
    monkeypatch: pytest.MonkeyPatch, force_heap: bool
) -> None:
    if force_heap:
        monkeypatch.setattr(astar, "MAX_BUCKET_COST_RATIO", 0.0)
    rng = np.random.default_rng(20240605)
    found = unreachable = 0
    for i in range(300):
        cost, start, goal = random_case(rng)
        for diagonal in (True, False):
            want = oracle_cost(cost, start, goal, diagonal)
            res = plan_verbose(cost, start, goal, diagonal=diagonal)
            if math.isinf(want):
                assert res.path is None, f"grid {i}: found a path the oracle does not have"
                assert res.status is not PlanStatus.FOUND
                unreachable += 1
                continue
            assert res.path is not None, f"grid {i}: no path ({res.reason}); oracle {want}"
            assert res.cost == pytest.approx(want, rel=1e-9, abs=0.0), f"grid {i}"
            check_path(cost, res.path, start, goal, diagonal)
            assert path_cost(cost, res.path) == pytest.approx(want, rel=1e-9, abs=0.0)
            found += 1
    assert found > 300 and unreachable > 30  # both outcomes well represented


def test_plan_returns_the_path_only() -> None:
    cost = np.ones((5, 7), np.float32)
    cost[1:4, 3] = np.inf
    path = plan(cost, (2, 0), (2, 6))
    assert path is not None and path.shape[1] == 2
    # around the wall: 6 columns to cross, detour over row 0 or row 4 is forbidden to cut
    assert path_cost(cost, path) == pytest.approx(oracle_cost(cost, (2, 0), (2, 6), True))


def test_reasons_when_there_is_no_path() -> None:
    cost = np.ones((6, 6), np.float32)
    cost[:, 3] = np.inf
    assert plan_verbose(cost, (0, 0), (0, 5)).status is PlanStatus.NO_PATH
    assert plan(cost, (0, 0), (0, 5)) is None
    assert plan_verbose(cost, (0, 3), (0, 0)).status is PlanStatus.START_BLOCKED
    assert plan_verbose(cost, (0, 0), (5, 3)).status is PlanStatus.GOAL_BLOCKED
    assert plan_verbose(cost, (-1, 0), (0, 0)).status is PlanStatus.START_OUTSIDE
    assert plan_verbose(cost, (0, 0), (0, 6)).status is PlanStatus.GOAL_OUTSIDE
    res = plan_verbose(cost, (0, 3), (0, 0))
    assert res.path is None and res.expanded == 0 and "start" in res.reason


def test_diagonal_gap_between_two_blocked_corners_is_closed() -> None:
    cost = np.ones((2, 2), np.float32)
    cost[0, 1] = cost[1, 0] = np.inf
    assert plan_verbose(cost, (0, 0), (1, 1)).status is PlanStatus.NO_PATH


def test_start_equals_goal() -> None:
    cost = np.full((3, 3), 2.0, np.float32)
    res = plan_verbose(cost, (1, 1), (1, 1))
    assert res.found and res.cost == 0.0 and res.path.tolist() == [[1, 1]]


@pytest.mark.parametrize("bad", [np.nan, 0.0, -1.0, -np.inf])
def test_bad_cost_values_are_refused(bad: float) -> None:
    cost = np.ones((4, 4), np.float32)
    cost[2, 2] = bad
    with pytest.raises(ValueError, match="positive"):
        plan(cost, (0, 0), (3, 3))


def test_wrong_dtype_is_refused() -> None:
    with pytest.raises(ValueError, match="float32"):
        plan(np.ones((4, 4)), (0, 0), (3, 3))


def test_open_grid_search_stays_on_the_optimal_band() -> None:
    """Equal-cost paths tie exactly: an open-grid query expands about one cell per step."""
    cost = np.ones((400, 400), np.float32)
    res = plan_verbose(cost, (390, 150), (10, 210))
    assert res.cost == pytest.approx(320 + 60 * math.sqrt(2.0), rel=1e-12)
    assert res.expanded < 2 * len(res.path)


def test_kept_scratch_gives_the_results_of_fresh_memory(monkeypatch: pytest.MonkeyPatch) -> None:
    """Searches in the memory kept between searches (grids of all sizes, one after another)
    find what searches in fresh zero pages find, and leave the kept memory clean."""
    rng = np.random.default_rng(7)
    cases = [random_case(rng) for _ in range(60)]
    kept = [plan_verbose(cost, s, t, diagonal=bool(i % 2)) for i, (cost, s, t) in enumerate(cases)]
    assert astar._kept and not astar._kept[0].g.any()
    monkeypatch.setattr(astar, "KEPT_CELLS", 0)
    for i, (cost, s, t) in enumerate(cases):
        fresh = plan_verbose(cost, s, t, diagonal=bool(i % 2))
        assert (fresh.status, fresh.cost, fresh.expanded) == (
            kept[i].status,
            kept[i].cost,
            kept[i].expanded,
        )
        if fresh.path is not None:
            assert kept[i].path is not None
            assert np.array_equal(fresh.path, kept[i].path)
