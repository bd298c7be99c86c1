"""Where an episode's time goes besides physics: world building, tree loading, ticking.

Runs the seeds of a scenario in this process through ``bt_manip.bench.episodes.run_one`` (as
``bt-manip bench --jobs 1`` does), after one warm-up episode (seed + 100) that fills what a
process keeps between episodes. Each part is timed around the function that does it, in wall
time and in CPU time of this thread (less disturbed by other programs on a busy machine):

- ``physics``: ``pybullet.stepSimulation``;
- ``step_rest``: the rest of ``World.step`` (the clock, contacts of attached objects);
- ``world``: building the World (world file, PyBullet bodies, robots);
- ``tree``: loading the tree;
- ``tick``: ``Tree.tick`` (every node's work, navigation and IK included), of which
  ``maps`` (a navigator's grids and carry layers), ``pose_search`` (the search over poses of a
  carrying robot) and ``ik_setup`` (building IK solvers);
- ``rest``: the episode's time outside all of these (report, closing the world).

    .venv/bin/python benchmarks/episode_overhead.py [--scenario A] [--seeds 5] [--first-seed 0]

Prints one JSON line per episode and one with the medians (milliseconds).
"""

from __future__ import annotations

import argparse
import functools
import json
import statistics
import time
from collections.abc import Callable
from typing import Any

import pybullet

import bt_manip.bench.episodes as bench
from bt_manip.cli.args import positive
from bt_manip.episode import EpisodeSpec

SCENARIOS = {
    "A": ("trees/husky_carry_wall.xml", "worlds/tb3_house.yaml"),
    "B": ("trees/sawyer_blocks_to_bin.xml", "worlds/sawyer_table.yaml"),
    "adaptive": ("trees/husky_carry_wall_adaptive.xml", "worlds/tb3_house.yaml"),
    "panda": ("trees/panda_pick_place.xml", "worlds/panda_table.yaml"),
}

Clocks = dict[str, list[float]]  # part -> [wall, cpu]


def timed(owner: Any, attr: str, part: str, clocks: Clocks) -> None:
    """Replace ``owner.attr`` by a version that adds its wall and CPU time to ``part``."""
    original: Callable[..., Any] = getattr(owner, attr)

    @functools.wraps(original)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        wall0, cpu0 = time.perf_counter(), time.thread_time()
        try:
            return original(*args, **kwargs)
        finally:
            entry = clocks.setdefault(part, [0.0, 0.0])
            entry[0] += time.perf_counter() - wall0
            entry[1] += time.thread_time() - cpu0

    setattr(owner, attr, wrapper)


def instrument(clocks: Clocks) -> None:
    import bt_manip.behaviours  # registers the nodes, imports what is timed
    import bt_manip.bt
    import bt_manip.navigation.navigator as navigator
    from bt_manip.bt.tree import Tree
    from bt_manip.kinematics.ik import IKSolver
    from bt_manip.sim.world import World

    timed(pybullet, "stepSimulation", "physics", clocks)
    timed(World, "step", "step_total", clocks)
    timed(World, "__init__", "world", clocks)
    timed(bt_manip.bt, "load_tree", "tree", clocks)
    timed(Tree, "tick", "tick", clocks)
    timed(navigator.Navigator, "__init__", "maps", clocks)
    timed(navigator.Navigator, "_build_carry_layers", "maps", clocks)
    timed(navigator, "plan_poses", "pose_search", clocks)
    timed(IKSolver, "__init__", "ik_setup", clocks)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenario", choices=sorted(SCENARIOS), default="A")
    ap.add_argument("--seeds", type=positive(int), default=5)
    ap.add_argument("--first-seed", type=int, default=0)
    args = ap.parse_args()
    tree, world = SCENARIOS[args.scenario]
    clocks: Clocks = {}
    instrument(clocks)
    bench.run_one(EpisodeSpec(tree=tree, world=world, seed=args.first_seed + 100))
    rows = []
    for seed in range(args.first_seed, args.first_seed + args.seeds):
        clocks.clear()
        wall0, cpu0 = time.perf_counter(), time.thread_time()
        result = bench.run_one(EpisodeSpec(tree=tree, world=world, seed=seed))
        total = [time.perf_counter() - wall0, time.thread_time() - cpu0]
        get = lambda part, i: clocks.get(part, [0.0, 0.0])[i]  # noqa: E731
        row: dict[str, Any] = {"scenario": args.scenario, "seed": seed,
                               "status": result.status, "sim_time": result.sim_time}
        for i, clock in enumerate(("wall", "cpu")):
            ms = {part: 1000.0 * get(part, i) for part in
                  ("physics", "world", "tree", "tick", "maps", "pose_search", "ik_setup")}
            ms["step_rest"] = 1000.0 * (get("step_total", i) - get("physics", i))
            ms["rest"] = 1000.0 * total[i] - (ms["physics"] + ms["step_rest"] + ms["world"]
                                              + ms["tree"] + ms["tick"])
            ms["total"] = 1000.0 * total[i]
            ms["not_physics"] = ms["total"] - ms["physics"]
            row[clock] = {k: round(v, 1) for k, v in ms.items()}
        rows.append(row)
        print(json.dumps(row), flush=True)
    medians = {clock: {k: round(statistics.median(r[clock][k] for r in rows), 1)
                       for k in rows[0][clock]} for clock in ("wall", "cpu")}
    print(json.dumps({"scenario": args.scenario, "episodes": len(rows), "median_ms": medians}))


if __name__ == "__main__":
    main()
