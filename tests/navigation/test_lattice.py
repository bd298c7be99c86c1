"""Pose planning for a long footprint: it must back away from a wall before it can turn."""

from __future__ import annotations

import math

import numpy as np

from bt_manip.navigation.costmap import clearance
from bt_manip.navigation.distance import squared_distances
from bt_manip.navigation.footprint import PlanarFootprint
from bt_manip.navigation.grid import OccupancyGrid
from bt_manip.navigation.lattice import (
    BACKWARD,
    TURN,
    LatticeOptions,
    clearance_at_least,
    outline_samples,
    plan_poses,
)
from bt_manip.navigation.lattice_search import GoalField, _heuristic, _move
from bt_manip.navigation.shapes import Disc


def room(corridor: bool = False) -> OccupancyGrid:
    """8 m x 4 m with 10 cm walls; with ``corridor`` the east half is a 1.2 m wide corridor."""
    grid = OccupancyGrid.empty((0.0, 0.0, 8.0, 4.0), 0.05)
    occ = grid.occupied
    occ[:, :2] = occ[:, -2:] = occ[:2, :] = occ[-2:, :] = True
    if corridor:
        occ[:28, 80:] = occ[52:, 80:] = True  # y < 1.4 and y > 2.6 for x > 4
    return grid


def test_long_footprint_backs_up_before_turning() -> None:
    grid = room(corridor=True)
    clear = clearance(grid)
    # a base carrying a load ahead of it: 2 m long, 0.5 m wide; it cannot turn in the corridor
    fp = PlanarFootprint.rectangle(2.0, 0.5, x_offset=0.7, label="base + load")
    start = (6.0, 2.0, 0.0)  # in the corridor, the load's front 0.2 m from the east wall
    goal = (2.2, 2.0, math.pi)
    plan = plan_poses(grid, clear, fp, start, goal)
    assert plan.ok, plan.reason
    assert plan.poses is not None and plan.moves is not None
    assert BACKWARD in plan.moves.tolist()
    first_turn = plan.moves.tolist().index(TURN) if TURN in plan.moves else len(plan.moves)
    assert BACKWARD in plan.moves[:first_turn].tolist()  # it backs up before turning on the spot
    end = plan.poses[-1]
    assert math.hypot(end[0] - goal[0], end[1] - goal[1]) <= 0.15
    assert abs((end[2] - goal[2] + math.pi) % (2 * math.pi) - math.pi) <= 0.2
    # every pose keeps the whole outline off the walls
    for rows, cols in _outline_cells(fp, plan.poses):
        assert not grid.occupied[rows, cols].any()


def _outline_cells(fp: PlanarFootprint, poses: np.ndarray) -> list[tuple[np.ndarray, np.ndarray]]:
    """The rows and columns (5 cm cells from the origin) of the footprint's outline samples
    at each pose."""
    pts = outline_samples(fp)
    out = []
    for x, y, th in poses:
        c, s = math.cos(th), math.sin(th)
        wx = x + c * pts[:, 0] - s * pts[:, 1]
        wy = y + s * pts[:, 0] + c * pts[:, 1]
        cells = np.floor(np.column_stack([wy, wx]) / 0.05).astype(int)
        out.append((cells[:, 0], cells[:, 1]))
    return out


def test_no_room_is_reported() -> None:
    grid = room()
    fp = PlanarFootprint.rectangle(4.5, 0.5, x_offset=1.5, label="base + beam")
    plan = plan_poses(grid, clearance(grid), fp, (1.0, 2.0, 0.0), (1.0, 2.0, math.pi / 2))
    assert not plan.ok
    assert "base + beam" in plan.reason and "goal" in plan.reason


def test_outline_samples_cover_the_boundary() -> None:
    fp = PlanarFootprint.rectangle(1.0, 0.5)
    pts = outline_samples(fp, 0.05)
    assert np.isclose(np.abs(pts[:, 0]).max(), 0.5) and np.isclose(np.abs(pts[:, 1]).max(), 0.25)
    # consecutive samples at most 5 cm apart around the outline
    ring = np.vstack([pts, pts[:1]])
    assert np.hypot(*np.diff(ring, axis=0).T).max() <= 0.05 + 1e-9


def reference_goal_distances(free: np.ndarray, goal: tuple[int, int]) -> np.ndarray:
    """Dijkstra (scipy) over free cells, 8-connected, no diagonal past a blocked side cell."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import dijkstra

    rows, cols = free.shape
    ids = np.arange(rows * cols).reshape(rows, cols)
    pad = np.zeros((rows + 2, cols + 2), bool)
    pad[1:-1, 1:-1] = free
    src, dst, wts = [], [], []
    for dr in (-1, 0, 1):
        for dc in (-1, 0, 1):
            if not (dr or dc):
                continue
            ok = free & pad[1 + dr : 1 + dr + rows, 1 + dc : 1 + dc + cols]
            if dr and dc:
                ok &= pad[1 + dr : 1 + dr + rows, 1 : 1 + cols]
                ok &= pad[1 : 1 + rows, 1 + dc : 1 + dc + cols]
            r, c = np.nonzero(ok)
            src.append(ids[r, c])
            dst.append(ids[r + dr, c + dc])
            wts.append(np.full(len(r), math.sqrt(2.0) if dr and dc else 1.0))
    n = rows * cols
    graph = coo_matrix((np.concatenate(wts), (np.concatenate(src), np.concatenate(dst))), (n, n))
    return dijkstra(graph.tocsr(), directed=True, indices=ids[goal]).reshape(rows, cols)


def test_goal_field_computed_on_demand_equals_the_whole_search() -> None:
    rng = np.random.default_rng(5)
    for _ in range(30):
        rows, cols = (int(v) for v in rng.integers(2, 50, 2))
        free = rng.random((rows, cols)) > float(rng.choice([0.0, 0.1, 0.3, 0.5]))
        goal = (int(rng.integers(rows)), int(rng.integers(cols)))
        whole = GoalField(free, goal).whole()
        ref = reference_goal_distances(free, goal) if free[goal] else np.full(free.shape, np.inf)
        assert np.array_equal(np.isinf(whole), np.isinf(ref))
        assert np.allclose(whole[np.isfinite(ref)], ref[np.isfinite(ref)], rtol=1e-12, atol=0)
        lazy = GoalField(free, goal)
        for _ in range(40):  # queries in any order get the final distance at once
            r, c = int(rng.integers(rows)), int(rng.integers(cols))
            h, lazy.heap_d, lazy.heap_i = _heuristic(
                (c + 0.5) * 0.05, (r + 0.5) * 0.05, 0.0, 0.0, 0.05, np.array([0.0, 0.0, 0.0]),
                lazy.free, lazy.dist, lazy.heap_d, lazy.heap_i, lazy.state, lazy.frontier,
            )
            if np.isfinite(whole[r, c]):
                assert h == whole[r, c] * 0.05
        assert np.array_equal(lazy.whole(), whole)


def test_squared_distances_plan_the_same_poses_as_the_clearance_grid() -> None:
    grid = room(corridor=True)
    d2 = squared_distances(grid.occupied)
    assert d2 is not None
    fp = PlanarFootprint.rectangle(1.6, 0.5, 0.5)
    goals = ((6.0, 2.0, 0.0), (2.0, 2.0, math.pi / 2), (3.0, 1.0, math.pi), (5.5, 2.0, math.pi))
    for goal in (*goals, (7.0, 3.5, 0.0)):  # the last one does not fit
        a = plan_poses(grid, clearance(grid), fp, (1.5, 2.0, 0.0), goal, 0.1)
        b = plan_poses(grid, d2, fp, (1.5, 2.0, 0.0), goal, 0.1)
        assert (a.ok, a.reason, a.expanded) == (b.ok, b.reason, b.expanded)
        assert a.ok == (goal in goals)
        if a.ok:
            assert a.poses is not None and b.poses is not None
            assert a.poses.tobytes() == b.poses.tobytes()
            assert np.array_equal(a.moves, b.moves)
    half = clearance(grid) >= 0.3
    assert np.array_equal(clearance_at_least(d2, grid.resolution, 0.3), half)


def _margin(grid: OccupancyGrid, clear: np.ndarray, fp: PlanarFootprint, pose: np.ndarray) -> float:
    """The smallest clearance (m) of the grid cells under the footprint's outline at ``pose``."""
    pts = outline_samples(fp)
    x, y, th = pose
    c, s = math.cos(th), math.sin(th)
    cols = np.floor((x + c * pts[:, 0] - s * pts[:, 1]) / grid.resolution).astype(int)
    rows = np.floor((y + s * pts[:, 0] + c * pts[:, 1]) / grid.resolution).astype(int)
    return float(clear[rows, cols].min())


def test_a_start_closer_than_the_margin_is_planned_out_of_first() -> None:
    grid = room()
    # a low box 0.4 m long beside the front of the base's left side, 6 cm off it: within the
    # 5 cm margin and the half cell a point may lie off its cell's centre
    grid.occupied[46:48, 60:68] = True  # x 3.0-3.4, y 2.3-2.4
    clear = clearance(grid)
    fp = PlanarFootprint.rectangle(1.0, 0.6, label="base")
    start = (3.0, 2.3 - 0.3 - 0.06, 0.0)
    goal = (6.0, 1.0, 0.0)
    assert _margin(grid, clear, fp, np.array(start)) < 0.05 + grid.resolution / math.sqrt(2)
    plan = plan_poses(grid, clear, fp, start, goal)
    assert plan.ok, plan.reason
    assert plan.poses is not None
    margins = [_margin(grid, clear, fp, p) for p in plan.poses]
    need = 0.05 + grid.resolution / math.sqrt(2)
    out = next(i for i, m in enumerate(margins) if m >= need)
    # off the wall all the way, and once the margin is back it is kept
    assert min(margins) >= grid.resolution / math.sqrt(2)
    assert min(margins[out:]) >= need
    # the margin is back within 0.6 m of the start
    assert math.hypot(plan.poses[out][0] - start[0], plan.poses[out][1] - start[1]) <= 0.6 + 0.2
    end = plan.poses[-1]
    assert math.hypot(end[0] - goal[0], end[1] - goal[1]) <= 0.15


def test_a_start_touching_an_obstacle_is_refused() -> None:
    grid = room()
    grid.occupied[46:48, 60:68] = True  # x 3.0-3.4, y 2.3-2.4
    clear = clearance(grid)
    fp = PlanarFootprint.rectangle(1.0, 0.6, label="base")
    start = (3.0, 2.3 - 0.3 + 0.02, 0.0)  # 2 cm into the box
    plan = plan_poses(grid, clear, fp, start, (6.0, 1.0, 0.0))
    assert not plan.ok
    assert plan.reason.endswith("touches obstacles at the start")


def _reversals(poses: np.ndarray) -> int:
    """How many times the heading changes from turning one way to the other (or to none)."""
    d = np.diff(np.unwrap(poses[:, 2]))
    sign = np.sign(np.where(np.abs(d) < 1e-6, 0.0, d))
    return int(np.sum(sign[1:] != sign[:-1]))


def test_a_carry_through_a_doorway_keeps_its_heading_and_its_moves_join_up() -> None:
    """A base with a 1.2 m panel across its front drives through a 1.4 m door: the plan turns
    where it must, not back and forth between neighbouring headings (which a follower cuts
    across, swinging the panel's ends), and each pose is reached from the one before by one
    lattice move (an expanded pose is never replaced by another of its bin)."""
    grid = room()
    grid.occupied[:26, 80:82] = True  # a partition at x = 4 with a door at y 1.3-2.7
    grid.occupied[54:, 80:82] = True
    clear = clearance(grid)
    base = PlanarFootprint.rectangle(0.9, 0.6, label="base")
    panel = PlanarFootprint.rectangle(0.3, 1.2, x_offset=0.6, label="panel")
    goal = (6.0, 2.0, 0.0)
    plan = plan_poses(
        grid, clear, base, (1.2, 0.8, 0.5), goal, 0.2, carried=panel, clear_high=clear
    )
    assert plan.ok, plan.reason
    assert plan.poses is not None and plan.moves is not None
    end = plan.poses[-1]
    assert math.hypot(end[0] - goal[0], end[1] - goal[1]) <= 0.15
    # without a cost for changing moves the heading turned one way then the other 16 times
    assert _reversals(plan.poses) <= 8
    o = LatticeOptions()
    moves = [(k, c, o.step) for k in (0, 1) for c in (0.0, 1 / o.turn_radius, -1 / o.turn_radius)]
    moves += [(2, 0.0, o.turn_step), (2, 0.0, -o.turn_step)]
    for a, b in zip(plan.poses[:-1], plan.poses[1:], strict=True):
        reached = [_move(a[0], a[1], a[2], k, c, length, 0.2, 1.0) for k, c, length in moves]
        gap = min(
            math.hypot(r[0] - b[0], r[1] - b[1]) + abs(math.remainder(r[2] - b[2], math.tau))
            for r in reached
        )
        assert gap < 1e-6


def test_outline_samples_are_even_steps_along_each_edge() -> None:
    # each edge a -> b of each outline (discs by their 48-gon) gives n = ceil(|b - a| / spacing)
    # samples a + (k / n) (b - a), k = 0 .. n - 1, in order, to the last bit
    box = PlanarFootprint.rectangle(1.23, 0.47, x_offset=0.31)
    fp = PlanarFootprint((*box.outlines, Disc(0.4, -0.1, 0.137)), "base + mast")
    for spacing in (0.05, 0.031):
        expected = []
        for o in fp.outlines:
            ring = o.points(48)
            for a, b in zip(ring, np.roll(ring, -1, axis=0), strict=True):
                n = max(1, math.ceil(float(np.hypot(*(b - a))) / spacing))
                expected.append(a + (np.arange(n)[:, None] / n) * (b - a))
        got = outline_samples(fp, spacing)
        assert got.tobytes() == np.concatenate(expected).tobytes()


def test_a_doorway_only_a_little_wider_than_the_base_is_passed_with_the_smaller_margin() -> None:
    grid = room()
    grid.occupied[:33, 80:82] = True  # a partition at x = 4.0-4.1, its door at y 1.65-2.40
    grid.occupied[48:, 80:82] = True
    clear = clearance(grid)
    base = PlanarFootprint.rectangle(0.9, 0.6, label="base")  # 7.5 cm to spare each side
    start, goal = (1.5, 2.025, 0.0), (6.5, 2.025, 0.0)
    strict = LatticeOptions(squeeze_clearance=LatticeOptions().min_clearance)
    refused = plan_poses(grid, clear, base, start, goal, options=strict)
    assert not refused.ok and "no sequence of moves" in refused.reason
    plan = plan_poses(grid, clear, base, start, goal)
    assert plan.ok, plan.reason
    assert plan.margin == LatticeOptions().squeeze_clearance
    assert plan.poses is not None
    assert plan.poses[0][0] < 4.0 < plan.poses[-1][0]  # through the door
    # every pose keeps the smaller margin: each outline point's cell is at least that far
    # (less the point's own offset in its cell) from the nearest blocked cell
    for rows, cols in _outline_cells(base, plan.poses):
        assert (clear[rows, cols] >= plan.margin).all()


def test_no_plan_with_either_margin_gives_the_first_search_s_reason() -> None:
    grid = room()
    grid.occupied[:, 80:82] = True  # a partition with no door at all
    plan = plan_poses(grid, clearance(grid), PlanarFootprint.rectangle(0.9, 0.6, label="base"),
                      (1.5, 2.0, 0.0), (6.5, 2.0, 0.0))
    assert not plan.ok and "no sequence of moves fits the footprint (base" in plan.reason
    assert math.isnan(plan.margin)
