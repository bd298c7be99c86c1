"""The ``coverage`` verb: which branches and recoveries of a tree a bench exercised.

``bt-manip coverage BENCH_DIR`` prints the coverage of the bench (or sweep) whose outputs are in
BENCH_DIR (its coverage.json, :mod:`bt_manip.bench.coverage`): branches covered / total, nodes
ticked, and each recovery that never ran with its path and line in the XML. ``--all`` lists
every branch; ``--diff OTHER_DIR`` compares it with another bench (OTHER_DIR first, as the
baseline); ``--min RATIO`` makes it usable as a check in CI.

Exit codes: 0, or 1 when the branch coverage is under ``--min``; 2 bad input (no coverage.json
in the folder).
"""

from __future__ import annotations

import argparse

from bt_manip.bench.coverage import branches_text, coverage_diff, coverage_text, read_coverage
from bt_manip.cli.args import within


def add_coverage_arguments(coverage: argparse.ArgumentParser) -> None:
    """The arguments of ``bt-manip coverage BENCH_DIR [--min R] [--diff OTHER_DIR] [--all]``."""
    coverage.description = (
        "Print which branches and recoveries of the tree a bench exercised (from its "
        "coverage.json). Exit codes: 0, 1 when the branch coverage is under --min, 2 bad input.")
    coverage.add_argument("bench", metavar="BENCH_DIR",
                          help="a bench's (or sweep's) --out folder, holding coverage.json")
    coverage.add_argument("--min", type=within(float, 0.0, 1.0), default=None, metavar="RATIO",
                          help="exit 1 when the share of branches that ran is under RATIO "
                          "(0..1, e.g. 0.8)")
    coverage.add_argument("--diff", metavar="OTHER_DIR",
                          help="compare with the bench in OTHER_DIR (the baseline): branches "
                          "that ran in one only, and in how many episodes each ran")
    coverage.add_argument("--all", action="store_true",
                          help="list every branch with the episodes it ran and won in")
    coverage.set_defaults(func=cmd_coverage)


VERB_ARGUMENTS = {"coverage": add_coverage_arguments}
"""The verbs of this module and the function that adds each one's arguments."""


def cmd_coverage(args: argparse.Namespace) -> int:
    """The ``coverage`` verb (see the module docstring for its exit codes)."""
    data = read_coverage(args.bench)
    other = read_coverage(args.diff) if args.diff else None
    print(coverage_text(data, shown=10_000))
    if args.all:
        print(branches_text(data))
    if other is not None:
        print(coverage_diff(other, data, (args.diff, args.bench)))
    if args.min is not None:
        b = data["branch_coverage"]
        ratio = b["covered"] / b["total"] if b["total"] else 1.0
        if ratio < args.min:
            print(f"branch coverage {100 * ratio:.1f} % is under --min "
                  f"{100 * args.min:g} %")
            return 1
    return 0
