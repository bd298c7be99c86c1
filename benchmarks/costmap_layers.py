"""What the laser-fed costmap layers cost a localised run: Scenario A with ``--localize``,
with the layers (the default when localising) and without them (the navigator drawing the
movable objects from the world's geometry, as before the layers), side by side in one run.

Run: ``.venv/bin/python benchmarks/costmap_layers.py [--seeds 6] [--first-seed 0]
[--tree trees/husky_carry_wall.xml] [--world worlds/tb3_house.yaml] [--inject block:0.5]``

For each seed the two variants run one after the other (their order alternating from seed to
seed, so that a machine's load drifts on both alike); the same episode otherwise (tree, world,
seed, faults). Each run's real-time factor (sim time / wall time of the tick loop) and CPU time
of the process per sim second are taken; with the layers, the wall time spent in the costmaps'
updates (casting the extra scans they take between the filter's, ray tracing, marking) is
timed too. One JSON line per variant: the medians, the successes, and for the layers the mean
milliseconds per costmap update and the updates per run.
"""

from __future__ import annotations

import argparse
import json
import statistics
import time
from pathlib import Path
from typing import Any

from bt_manip.cli.args import positive
from bt_manip.episode import Episode, EpisodeSpec
from bt_manip.run.faults import parse_fault

ROOT = Path(__file__).resolve().parent.parent


def run_one(spec: EpisodeSpec, layers: bool) -> dict[str, Any]:
    """One episode with the layers on or off: RTF, CPU s per sim s, status, update timings."""
    spent = {"s": 0.0, "n": 0}
    with Episode(spec) as episode:
        assert episode.localization is not None
        for loc in episode.localization.localizers.values():
            if not layers:
                loc.costmaps = None  # the navigator then draws movable objects from the world
                continue
            feed = loc._feed_costmaps

            def timed(now: float, feed: Any = feed) -> None:
                t = time.perf_counter()
                feed(now)
                spent["s"] += time.perf_counter() - t
                spent["n"] += 1

            loc._feed_costmaps = timed  # type: ignore[method-assign]
        cpu = time.process_time()
        report = episode.run()
        cpu = time.process_time() - cpu
    return {"rtf": report.real_time_factor, "cpu_per_sim_s": cpu / max(report.sim_time, 1e-9),
            "ok": report.status.value == "SUCCESS", "update_s": spent["s"],
            "updates": spent["n"]}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seeds", type=positive(int), default=6)
    parser.add_argument("--first-seed", type=int, default=0)
    parser.add_argument("--tree", default=str(ROOT / "trees" / "husky_carry_wall.xml"))
    parser.add_argument("--world", default=str(ROOT / "worlds" / "tb3_house.yaml"))
    parser.add_argument("--inject", action="append", default=[])
    args = parser.parse_args()
    faults = [parse_fault(t) for t in args.inject]
    rows: dict[bool, list[dict[str, Any]]] = {True: [], False: []}
    for k in range(args.seeds):
        seed = args.first_seed + k
        spec = EpisodeSpec(tree=args.tree, world=args.world, seed=seed, localize=True,
                           inject=faults)
        order = (True, False) if k % 2 == 0 else (False, True)
        for layers in order:
            rows[layers].append(run_one(spec, layers))
    for layers in (True, False):
        r = rows[layers]
        line: dict[str, Any] = {
            "variant": "layers" if layers else "no layers (movable objects from the world)",
            "tree": Path(args.tree).name, "world": Path(args.world).name,
            "inject": args.inject, "seeds": len(r),
            "successes": sum(x["ok"] for x in r),
            "median_rtf": round(statistics.median(x["rtf"] for x in r), 2),
            "median_cpu_s_per_sim_s": round(statistics.median(x["cpu_per_sim_s"] for x in r), 4),
        }
        if layers:
            n = sum(x["updates"] for x in r)
            line["ms_per_costmap_update"] = round(1000 * sum(x["update_s"] for x in r) / max(n, 1),
                                                  3)
            line["costmap_updates_per_run"] = round(n / len(r), 1)
        print(json.dumps(line), flush=True)


if __name__ == "__main__":
    main()
