"""Real-time factor of the scenarios, two checkouts of bt-manip side by side.

Each checkout runs the same seeds of Scenario A (``trees/husky_carry_wall.xml`` on
``worlds/tb3_house.yaml``) and Scenario B (``trees/sawyer_blocks_to_bin.xml`` on
``worlds/sawyer_table.yaml``) through its own ``run_bench`` (``bt_manip.bench.pool``) with one
job, as ``bt-manip bench --jobs 1`` does, in a fresh Python process started in that checkout. The
checkouts take turns, round after round and in alternating order, so that the load other
programs put on the machine falls on both alike.

Every episode is timed the same way whatever the checkout's bench reports: wall and CPU time
from before its world is built to after its report is made (``run_one``), so world loading is
included. The real-time factor of an episode is its sim time over that wall time; the table
gives medians over all episodes of all rounds. The checkout's own bench figure
(``bench_rtf``) is shown too (older checkouts time the ticks only). ``same_outcomes`` counts
the seeds whose status and sim time agree with the first checkout's.

    .venv/bin/python benchmarks/realtime_factor.py --checkout main=../wt-base --checkout new=. \
        [--seeds 10] [--first-seed 0] [--rounds 3] [--scenario A --scenario B] \
        [--blas-threads N]

Prints ``uptime`` before and after, a table, and one JSON line per scenario and checkout.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

SCENARIOS = {
    "A": ("trees/husky_carry_wall.xml", "worlds/tb3_house.yaml"),
    "B": ("trees/sawyer_blocks_to_bin.xml", "worlds/sawyer_table.yaml"),
}

DRIVER = r"""
import json, sys, time
try:
    import bt_manip.bench.pool as bench  # run_bench, and the run_one it calls
except ImportError:
    import bt_manip.bench as bench  # a checkout from before the bench package
from bt_manip.episode import EpisodeSpec

tree, world, first, runs = sys.argv[1], sys.argv[2], int(sys.argv[3]), int(sys.argv[4])
inner = bench.run_one

def timed(spec):
    wall0, cpu0 = time.perf_counter(), time.process_time()
    result = inner(spec)
    wall, cpu = time.perf_counter() - wall0, time.process_time() - cpu0
    print(json.dumps({"seed": result.seed, "status": result.status,
                      "sim_time": result.sim_time, "bench_wall": result.wall_time,
                      "wall": wall, "cpu": cpu}), flush=True)
    return result

bench.run_one = timed
bench.run_bench(EpisodeSpec(tree=tree, world=world, seed=first), runs, jobs=1)
"""


@dataclass
class Episode:
    checkout: str
    scenario: str
    seed: int
    status: str
    sim_time: float
    bench_wall: float
    wall: float
    cpu: float


def run_checkout(name: str, folder: Path, scenario: str, first: int, runs: int,
                 python: str, blas_threads: int | None) -> list[Episode]:
    tree, world = SCENARIOS[scenario]
    env = dict(os.environ, PYTHONPATH=str(folder))
    if blas_threads is not None:
        env["OPENBLAS_NUM_THREADS"] = env["OMP_NUM_THREADS"] = str(blas_threads)
    out = subprocess.run(
        [python, "-c", DRIVER, tree, world, str(first), str(runs)],
        cwd=folder, env=env, capture_output=True, text=True, check=False,
    )
    if out.returncode != 0:
        sys.exit(f"{name} ({folder}) failed:\n{out.stderr[-3000:]}")
    episodes = []
    for line in out.stdout.splitlines():
        if line.startswith("{"):
            d = json.loads(line)
            episodes.append(Episode(name, scenario, d["seed"], d["status"], d["sim_time"],
                                    d["bench_wall"], d["wall"], d["cpu"]))
    return episodes


def uptime() -> str:
    try:
        return subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip()
    except OSError:
        return "load: " + " ".join(f"{x:.2f}" for x in os.getloadavg())


def _count(text: str) -> int:
    """An argparse type: a whole number of at least 1 (this script imports no bt-manip: it
    measures other checkouts)."""
    try:
        n = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole number, got '{text}'") from None
    if n < 1:
        raise argparse.ArgumentTypeError(f"must be > 0, got {text}")
    return n


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--checkout", action="append", required=True, metavar="NAME=FOLDER",
                    help="a bt-manip checkout to measure (give two or more)")
    ap.add_argument("--scenario", action="append", choices=sorted(SCENARIOS))
    ap.add_argument("--seeds", type=_count, default=10)
    ap.add_argument("--first-seed", type=int, default=0)
    ap.add_argument("--rounds", type=_count, default=3)
    ap.add_argument("--python", default=sys.executable)
    ap.add_argument("--blas-threads", type=_count, default=None,
                    help="pin OpenBLAS/OpenMP threads in both checkouts (default: as set)")
    args = ap.parse_args()
    checkouts = []
    for item in args.checkout:
        name, _, folder = item.partition("=")
        if not folder or not (Path(folder) / "bt_manip").is_dir():
            ap.error(f"--checkout {item}: expected NAME=FOLDER, FOLDER holding bt_manip/")
        checkouts.append((name, Path(folder).resolve()))
    scenarios = args.scenario or sorted(SCENARIOS)
    print(f"# before: {uptime()}", flush=True)
    episodes: list[Episode] = []
    for r in range(args.rounds):
        order = checkouts if r % 2 == 0 else checkouts[::-1]
        for scenario in scenarios:
            for name, folder in order:
                got = run_checkout(name, folder, scenario, args.first_seed, args.seeds,
                                   args.python, args.blas_threads)
                episodes += got
                rtf = statistics.median(e.sim_time / e.wall for e in got)
                print(f"# round {r + 1} {scenario} {name}: median RTF {rtf:.1f}x "
                      f"({uptime()})", flush=True)
    print(f"# after: {uptime()}")
    print()
    print("| scenario | checkout | episodes | succeeded | same outcomes | median sim time | "
          "median wall time | median RTF | median CPU RTF | bench_rtf |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    lines = []
    for scenario in scenarios:
        reference = {(e.seed): (e.status, round(e.sim_time, 6)) for e in episodes
                     if e.scenario == scenario and e.checkout == checkouts[0][0]}
        for name, _ in checkouts:
            mine = [e for e in episodes if e.scenario == scenario and e.checkout == name]
            same = {e.seed for e in mine
                    if reference.get(e.seed) == (e.status, round(e.sim_time, 6))}
            seeds = {e.seed for e in mine}
            row = {
                "scenario": scenario, "checkout": name, "episodes": len(mine),
                "succeeded": sum(e.status == "SUCCESS" for e in mine),
                "same_outcomes": f"{len(same)}/{len(seeds)}",
                "median_sim_time": statistics.median(e.sim_time for e in mine),
                "median_wall_time": statistics.median(e.wall for e in mine),
                "median_rtf": statistics.median(e.sim_time / e.wall for e in mine),
                "median_cpu_rtf": statistics.median(e.sim_time / e.cpu for e in mine),
                "median_bench_rtf": statistics.median(e.sim_time / e.bench_wall for e in mine),
            }
            lines.append(row)
            print(f"| {scenario} | {name} | {row['episodes']} | {row['succeeded']} | "
                  f"{row['same_outcomes']} | {row['median_sim_time']:.2f} s | "
                  f"{row['median_wall_time']:.3f} s | {row['median_rtf']:.1f}x | "
                  f"{row['median_cpu_rtf']:.1f}x | {row['median_bench_rtf']:.1f}x |")
    print()
    for row in lines:
        print(json.dumps(row))


if __name__ == "__main__":
    main()
