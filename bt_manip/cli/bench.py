"""The ``bench`` verb: run a bench (or a sweep of benches), stream its episodes, resume it.

Exit codes: 0 every episode succeeded; 1 some did not (the statistics are still written);
2 bad input (tree, world, options, a log that cannot be resumed), nothing run; 130
interrupted (Ctrl-C or SIGTERM): the episodes that finished are in ``episodes.jsonl``, and
``bt-manip bench --resume DIR`` runs the rest. The work is :mod:`bt_manip.bench`'s.
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from bt_manip.bench.log import LOG_NAME
from bt_manip.bench.points import PoolOptions, new_points, resume_points, run_points
from bt_manip.bundled import shipped_or_given
from bt_manip.cli.args import (
    DEFAULT_MAX_SIM_TIME,
    DEFAULT_TICK_HZ,
    TICK_HZ,
    add_inject,
    add_localize,
    bb_pair,
    positive,
    within,
)
from bt_manip.cli.run import episode_spec
from bt_manip.episode import Episode
from bt_manip.errors import InputError, Problem
from bt_manip.outputs import check_output_folder, make_folder
from bt_manip.plugins import add_import_flag

DEFAULT_BENCH_OUT = "out/bench"
DEFINING: dict[str, Any] = {
    "tree": None, "world": None, "runs": 20, "seed": 0, "tree_id": None, "models": [], "bb": [],
    "max_ticks": None, "max_sim_time": DEFAULT_MAX_SIM_TIME, "tick_hz": DEFAULT_TICK_HZ,
    "inject": [], "imports": [], "sweep": None, "localize": False,
}
"""The options that define a bench, with their defaults (``--resume`` refuses them)."""


def add_bench_arguments(bench: argparse.ArgumentParser) -> None:
    """The arguments of ``bt-manip bench``."""
    bench.description = (
        "Run many seeded episodes of a tree and report statistics. Exit codes: 0 "
        "every episode succeeded, 1 some did not, 2 bad input, 130 interrupted (the finished "
        "episodes are kept in episodes.jsonl; --resume DIR runs the rest).")
    bench.add_argument("tree", nargs="?", type=shipped_or_given,
                       help="BehaviorTree.CPP v4 XML file")
    bench.add_argument("--world", type=shipped_or_given,
                       help="world file (YAML); required unless --resume")
    bench.add_argument("--runs", type=positive(int), default=DEFINING["runs"],
                       help="episodes (default 20)")
    bench.add_argument("--seed", type=int, default=0, help="seed of the first episode")
    bench.add_argument("--jobs", type=within(int, 1, 64), default=2,
                       help="worker processes, or CPUs of a local Ray instance (1..64)")
    bench.add_argument(
        "--out",
        default=DEFAULT_BENCH_OUT,
        help=f"folder for JSON, CSV and PNG output (default {DEFAULT_BENCH_OUT}; bt-manip creates "
        "at most this folder, its parent must exist)",
    )
    bench.add_argument(
        "--resume", metavar="DIR",
        help="finish the interrupted bench (or sweep) whose outputs are in DIR: run the seeds "
        "that have no episode in DIR/episodes.jsonl yet, with the same tree, world and options",
    )
    bench.add_argument(
        "--sweep", metavar="TEXT",
        help="run the bench once per value of an --inject text or bb:KEY=VALUE with {a,b,...} "
        "in place of one value, e.g. 'slip:{0,0.1,0.2}'; one folder per value in --out, and "
        "sweep.json/.csv/.png",
    )
    bench.add_argument("--backend", choices=("processes", "ray"), default="processes",
                       help="where episodes run: local worker processes (default) or Ray "
                       "(pip install 'bt-manip[ray]')")
    bench.add_argument("--address", metavar="ADDR",
                       help="with --backend ray: the cluster's address (default: start a local "
                       "instance with --jobs CPUs)")
    bench.add_argument("--tree-id")
    bench.add_argument("--models", action="append", default=[], metavar="MODELS.xml")
    bench.add_argument("--bb", action="append", type=bb_pair, default=[], metavar="KEY=VALUE")
    bench.add_argument("--max-ticks", type=positive(int))
    bench.add_argument("--max-sim-time", type=positive(float), default=DEFAULT_MAX_SIM_TIME,
                       metavar="S")
    bench.add_argument("--tick-hz", type=TICK_HZ, default=DEFAULT_TICK_HZ)
    bench.add_argument(
        "--btlog-failures",
        metavar="DIR",
        help="write DIR/seed-N.btlog for every episode that does not succeed (Groot2 replays it)",
    )
    add_inject(bench)
    add_localize(bench)
    add_import_flag(bench)
    bench.set_defaults(func=cmd_bench)


VERB_ARGUMENTS = {"bench": add_bench_arguments}
"""The verbs of this module and the function that adds each one's arguments."""


def _check_resume_args(args: argparse.Namespace) -> None:
    given = [name for name, default in DEFINING.items()
             if getattr(args, name, default) not in (default, None, [])]
    if given:
        flags = ", ".join("--" + g.replace("_", "-") if g not in ("tree",) else "TREE"
                          for g in given)
        raise InputError.single(
            "--resume", None, f"the bench's definition comes from {args.resume}/{LOG_NAME}; "
                              f"leave out {flags}")


def cmd_bench(args: argparse.Namespace) -> int:
    """The ``bench`` verb (see the module docstring for its exit codes)."""
    if args.address and args.backend != "ray":
        raise InputError.single("--address", None, "only with --backend ray")
    if (not args.resume and args.out == DEFAULT_BENCH_OUT
            and not Path(DEFAULT_BENCH_OUT).parent.exists()):
        make_folder(Path(DEFAULT_BENCH_OUT).parent)  # out/, bt-manip's own default folder
    if args.btlog_failures:
        check_output_folder("--btlog-failures", args.btlog_failures)
    if args.resume:
        _check_resume_args(args)
        sweep, points = resume_points(Path(args.resume))
    else:
        if not args.tree or not args.world:
            missing = [p for p, v in (("TREE", args.tree), ("--world", args.world)) if not v]
            raise InputError([Problem("bench", None, f"{' and '.join(missing)} required "
                                      "(or --resume DIR)")])
        check_output_folder("--out", args.out)
        base = episode_spec(args)
        with Episode(base):  # check the tree and world once, before starting workers
            pass
        seeds = [args.seed + i for i in range(args.runs)]
        sweep, points = new_points(base, seeds, Path(args.out), args.sweep)
    options = PoolOptions(jobs=args.jobs, backend=args.backend, address=args.address,
                          btlog_failures=args.btlog_failures, folder=args.resume or args.out)
    summaries = run_points(options, points, sweep)
    if args.btlog_failures:
        failed = sum(s.runs - s.successes for s in summaries)
        print(f"wrote {failed} .btlog file(s) of failed episodes to {args.btlog_failures}")
    return 0 if all(s.successes == s.runs for s in summaries) else 1
