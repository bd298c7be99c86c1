"""Grid A* side by side: bt-manip's planner, pyastar2d (C++) and tcod.path, in one run.

Run: ``.venv/bin/python benchmarks/astar.py [--repeat 5] [--queries 10] [--calls 3] [--no-house]
[--corners-only]``

Grids (1000 x 1000 unless named otherwise):

- ``open``: every cell costs 1.
- ``random20``: 20 % of the cells blocked at random, the rest cost 1.
- ``maze``: a perfect maze with one-cell corridors and walls (random depth-first carving).
- ``house``: the inflated cost grid of ``worlds/tb3_house.yaml`` for the Husky (323 x 223
  cells of 5 cm), with the cost gradient near obstacles (costs 1 to 7).

Corner to corner first: on ``open``, ``random20`` (seed 1) and ``maze``, one query from the free
cell nearest the top-left corner to the one nearest the bottom-right corner, bt-manip and
pyastar2d (tcod takes seconds a call there) each called
once to warm up and then ``--calls`` times, the calls of the planners taking turns; one line per
grid and planner with the median wall time (and CPU time: on a shared machine the process's own
CPU time says more), and on bt-manip's line its time over pyastar2d's (``time_vs_pyastar2d``,
``cpu_vs_pyastar2d``).

Then each grid gets the same seeded start/goal pairs for every planner (free cells, joined by a
path under bt-manip's rules). Every line printed is one JSON object: grid, planner, median
time per query (ms), and the mean path cost recomputed with bt-manip's cost definition
(``step_length x cost[entered cell]``, step_length 1 or sqrt 2), plus how many diagonal steps of
each peer's paths cut a blocked corner (which bt-manip forbids). How the peers define cost:

- pyastar2d: a move into cell b costs ``cost[b]`` whatever its direction (diagonals are not
  longer than side moves) and diagonals may pass blocked corners; its paths are optimal for that
  metric, so under ours they are longer.
- tcod.path (SimpleGraph): integer costs; a move costs ``cost[b] x cardinal`` or
  ``cost[b] x diagonal`` with (cardinal, diagonal) = (1000, 1414) here and costs scaled by 10
  and rounded; diagonals may pass blocked corners.
"""

from __future__ import annotations

import argparse
import json
import math
import statistics
import sys
import time
from collections.abc import Callable

import numpy as np

from bt_manip.cli.args import positive
from bt_manip.navigation import astar

Cell = tuple[int, int]


def open_grid(n: int = 1000) -> np.ndarray:
    return np.ones((n, n), np.float32)


def random_grid(n: int = 1000, blocked: float = 0.2, seed: int = 1) -> np.ndarray:
    rng = np.random.default_rng(seed)
    g = np.ones((n, n), np.float32)
    g[rng.random((n, n)) < blocked] = np.inf
    return g


def maze_grid(n: int = 1000, seed: int = 2) -> np.ndarray:
    """Perfect maze: cells at odd coordinates, carved by randomised depth-first search."""
    rng = np.random.default_rng(seed)
    m = (n - 1) // 2
    g = np.full((n, n), np.inf, np.float32)
    seen = np.zeros((m, m), bool)
    stack = [(0, 0)]
    seen[0, 0] = True
    g[1, 1] = 1.0
    moves = ((0, 1), (1, 0), (0, -1), (-1, 0))
    while stack:
        r, c = stack[-1]
        options = [
            (r + dr, c + dc)
            for dr, dc in moves
            if 0 <= r + dr < m and 0 <= c + dc < m and not seen[r + dr, c + dc]
        ]
        if not options:
            stack.pop()
            continue
        nr, nc = options[int(rng.integers(len(options)))]
        seen[nr, nc] = True
        g[2 * nr + 1, 2 * nc + 1] = 1.0
        g[r + nr + 1, c + nc + 1] = 1.0
        stack.append((nr, nc))
    return g


def house_grid() -> np.ndarray | None:
    """The Husky's planning cost grid of worlds/tb3_house.yaml (0.05 m cells), if it loads."""
    try:
        from bt_manip.navigation.navigator import Navigator
        from bt_manip.sim.world import World

        with World("worlds/tb3_house.yaml", seed=0) as world:
            nav = Navigator(world.robots["husky"], world.obstacle_body_ids(), world.movable)
            return nav.cost.copy()
    except Exception as exc:  # the world may not load on this checkout
        print(json.dumps({"grid": "house", "skipped": repr(exc)}), file=sys.stderr)
        return None


def queries(grid: np.ndarray, k: int, seed: int = 3) -> list[tuple[Cell, Cell]]:
    """k seeded start/goal pairs; the first joins two far corners' nearest free cells."""
    rng = np.random.default_rng(seed)
    free = np.argwhere(np.isfinite(grid))
    out: list[tuple[Cell, Cell]] = []
    first = free[np.argmin(free.sum(axis=1))], free[np.argmax(free.sum(axis=1))]
    candidates = [first]
    while len(out) < k:
        if candidates:
            a, b = candidates.pop()
        else:
            a, b = free[rng.integers(len(free))], free[rng.integers(len(free))]
        s, t = (int(a[0]), int(a[1])), (int(b[0]), int(b[1]))
        if s != t and astar.plan(grid, s, t) is not None:
            out.append((s, t))
    return out


def run_ours(grid: np.ndarray, s: Cell, t: Cell) -> np.ndarray | None:
    return astar.plan(grid, s, t, diagonal=True)


def make_pyastar2d() -> Callable[[np.ndarray, Cell, Cell], np.ndarray | None] | None:
    try:
        import pyastar2d
    except ImportError:
        return None

    def run(grid: np.ndarray, s: Cell, t: Cell) -> np.ndarray | None:
        return pyastar2d.astar_path(grid, s, t, allow_diagonal=True)

    return run


def make_tcod() -> Callable[[np.ndarray, Cell, Cell], np.ndarray | None] | None:
    try:
        import tcod.path
    except ImportError:
        return None

    def run(grid: np.ndarray, s: Cell, t: Cell) -> np.ndarray | None:
        icost = np.where(np.isfinite(grid), np.rint(grid * 10), 0).astype(np.int32)
        graph = tcod.path.SimpleGraph(cost=icost, cardinal=1000, diagonal=1414)
        pf = tcod.path.Pathfinder(graph)
        pf.add_root(s)
        p = pf.path_to(t)
        return None if len(p) == 0 or tuple(p[-1]) != t else np.asarray(p)

    return run


def measure(
    name: str,
    grid: np.ndarray,
    pairs: list[tuple[Cell, Cell]],
    planner: str,
    fn: Callable[[np.ndarray, Cell, Cell], np.ndarray | None],
    repeat: int,
) -> dict[str, object]:
    times: list[float] = []
    costs: list[float] = []
    cuts = 0
    failed = 0
    for s, t in pairs:
        best = math.inf
        path = None
        for _ in range(repeat):
            t0 = time.perf_counter()
            path = fn(grid, s, t)
            best = min(best, time.perf_counter() - t0)
        times.append(best)
        if path is None:
            failed += 1
            continue
        costs.append(astar.path_cost(grid, path))
        cuts += astar.corner_cuts(grid, path)
    return {
        "grid": name,
        "shape": list(grid.shape),
        "planner": planner,
        "queries": len(pairs),
        "median_ms": round(statistics.median(times) * 1e3, 3),
        "max_ms": round(max(times) * 1e3, 3),
        "mean_cost": round(statistics.fmean(costs), 4) if costs else None,
        "corner_cuts": cuts,
        "failed": failed,
    }


def corner_cells(grid: np.ndarray) -> tuple[Cell, Cell]:
    """The free cells nearest the top-left and the bottom-right corner."""
    free = np.argwhere(np.isfinite(grid))
    a, b = free[np.argmin(free.sum(axis=1))], free[np.argmax(free.sum(axis=1))]
    return (int(a[0]), int(a[1])), (int(b[0]), int(b[1]))


def corner_to_corner(
    name: str,
    grid: np.ndarray,
    planners: dict[str, Callable[[np.ndarray, Cell, Cell], np.ndarray | None]],
    calls: int,
) -> list[dict[str, object]]:
    """One corner-to-corner query per planner: a warm-up call, then ``calls`` timed calls."""
    s, t = corner_cells(grid)
    times: dict[str, list[float]] = {p: [] for p in planners}
    cpu: dict[str, list[float]] = {p: [] for p in planners}
    paths: dict[str, np.ndarray | None] = {}
    for p, fn in planners.items():
        paths[p] = fn(grid, s, t)
    for _ in range(calls):
        for p, fn in planners.items():
            c0 = time.process_time()
            t0 = time.perf_counter()
            fn(grid, s, t)
            times[p].append(time.perf_counter() - t0)
            cpu[p].append(time.process_time() - c0)
    rows: list[dict[str, object]] = []
    for p in planners:
        path = paths[p]
        rows.append(
            {
                "case": "corner_to_corner",
                "grid": name,
                "shape": list(grid.shape),
                "planner": p,
                "start": list(s),
                "goal": list(t),
                "calls": calls,
                "median_ms": round(statistics.median(times[p]) * 1e3, 3),
                "min_ms": round(min(times[p]) * 1e3, 3),
                "max_ms": round(max(times[p]) * 1e3, 3),
                "median_cpu_ms": round(statistics.median(cpu[p]) * 1e3, 3),
                "cost": None if path is None else round(astar.path_cost(grid, path), 4),
                "corner_cuts": None if path is None else astar.corner_cuts(grid, path),
            }
        )
    ours = float(rows[0]["median_ms"])  # type: ignore[arg-type]
    for row in rows:
        row["time_vs_bt_manip"] = round(float(row["median_ms"]) / ours, 3)  # type: ignore[arg-type]
    if "pyastar2d" in planners:
        peer = float(rows[list(planners).index("pyastar2d")]["median_ms"])  # type: ignore[arg-type]
        rows[0]["time_vs_pyastar2d"] = round(ours / peer, 3)
        ours_cpu = float(rows[0]["median_cpu_ms"])  # type: ignore[arg-type]
        peer_cpu = float(rows[list(planners).index("pyastar2d")]["median_cpu_ms"])  # type: ignore[arg-type]
        rows[0]["cpu_vs_pyastar2d"] = round(ours_cpu / peer_cpu, 3)
    return rows


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=positive(int), default=3, help="runs per query (best is kept)")
    ap.add_argument("--queries", type=positive(int), default=10, help="start/goal pairs per grid")
    ap.add_argument("--calls", type=positive(int), default=3, help="timed corner-to-corner calls")
    ap.add_argument("--no-house", action="store_true")
    ap.add_argument("--corners-only", action="store_true", help="skip the random queries")
    args = ap.parse_args(argv)

    t0 = time.perf_counter()
    astar.warm_up()
    print(json.dumps({"event": "first_call_s", "value": round(time.perf_counter() - t0, 3)}))

    grids: dict[str, np.ndarray] = {
        "open": open_grid(),
        "random20": random_grid(),
        "maze": maze_grid(),
    }
    if not args.no_house and not args.corners_only:
        house = house_grid()
        if house is not None:
            grids["house"] = house
    planners = {"bt_manip": run_ours}
    for label, maker in (("pyastar2d", make_pyastar2d), ("tcod", make_tcod)):
        fn = maker()
        if fn is not None:
            planners[label] = fn
    corner_planners = {p: fn for p, fn in planners.items() if p != "tcod"}  # seconds a call
    for name in ("open", "random20", "maze"):
        for row in corner_to_corner(name, grids[name], corner_planners, args.calls):
            print(json.dumps(row), flush=True)
    if args.corners_only:
        return
    for name, grid in grids.items():
        pairs = queries(grid, args.queries)
        rows = [measure(name, grid, pairs, p, fn, args.repeat) for p, fn in planners.items()]
        ours = rows[0]["median_ms"]
        for row in rows:
            row["time_vs_bt_manip"] = round(float(row["median_ms"]) / float(ours), 3)
            print(json.dumps(row), flush=True)


if __name__ == "__main__":
    main()
