"""Agreement of bt-manip with the real BehaviorTree.CPP 4.8.2 on random trees.

Generates N trees from a seed (tests/bt/differential), ticks each on both engines with the same
schedule and prints JSON lines: one per run with the figures (total, agree, mismatch, excluded
by rule, mismatches by cause after shrinking), then one per cause with its smallest example.

    python benchmarks/btcpp_differential.py --trees 20000 --seed 0 [--write-mismatches DIR]
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests" / "bt"))
sys.path.insert(0, str(ROOT))

from differential.campaign import run_campaign, write_mismatch_files  # noqa: E402

from bt_manip.cli.args import positive  # noqa: E402


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trees", type=positive(int), default=1000,
                        help="number of trees (default 1000)")
    parser.add_argument("--seed", type=int, default=0, help="first seed (default 0)")
    parser.add_argument("--shrink", type=int, default=200,
                        help="shrink at most this many mismatches (default 200)")
    parser.add_argument("--write-mismatches", type=Path, default=None, metavar="DIR",
                        help="write one NNN.md per cause into DIR")
    args = parser.parse_args(argv)
    if args.trees < 1:
        parser.error("--trees: must be at least 1")
    start = time.perf_counter()
    report = run_campaign(args.seed, args.trees, shrink_limit=args.shrink)
    figures = report.figures()
    figures.update(seed=args.seed, seconds=round(time.perf_counter() - start, 1))
    print(json.dumps({"run": figures}))
    for cause, group in report.by_cause().items():
        smallest = min(group, key=lambda m: m.shrunk.size())
        print(json.dumps({"cause": cause, "count": len(group), "seed": smallest.case.seed,
                          "xml": smallest.shrunk.xml(), "schedule": smallest.shrunk.schedule,
                          "difference": smallest.shrunk_divergence.describe()}))
    if args.write_mismatches is not None:
        write_mismatch_files(report, args.write_mismatches)
    return 0


if __name__ == "__main__":
    sys.exit(main())
