"""The ``motion-bench`` verb: plan an arm's MotionBenchMaker problems (one family folder, or a
folder of them), print the solved count and the planning time and path length figures per
family, and optionally write every problem's outcome and path (schema ``motion-bench``). The
work is :mod:`bt_manip.manipulation.motion_bench`'s.

Exit codes: 0 when every problem was read (solved or not), 2 on a file that cannot be read.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from bt_manip.cli.args import positive
from bt_manip.manipulation.motion_bench import (
    PLANNERS,
    BenchOptions,
    Outcome,
    family_folders,
    load_robot,
    results_document,
    run_bench,
    summary_lines,
)
from bt_manip.outputs import check_output_file, write_text


def add_motion_bench_arguments(parser: argparse.ArgumentParser) -> None:
    """The arguments of ``bt-manip motion-bench``."""
    parser.description = (
        "Plan every MotionBenchMaker problem (sceneNNNN.yaml + requestNNNN.yaml) of DIR, a "
        "family folder or a folder of them, with the arm of --urdf; check each path on the "
        "exact meshes at 0.01 rad per joint; print the solved count, median / mean / p95 "
        "planning time and path length per family and overall.")
    parser.add_argument("dir", metavar="DIR", help="a family folder (problems/box_panda/) or a "
                        "folder of family folders")
    parser.add_argument("--urdf", required=True, help="the robot's URDF (package:// and "
                        "relative mesh paths are resolved against its folder)")
    parser.add_argument("--srdf", default=None, help="its SRDF: planning groups and the link "
                        "pairs never checked (default: plan the joints each goal constrains)")
    parser.add_argument("--group", default=None, metavar="NAME",
                        help="SRDF group to plan (default: each request's group_name)")
    parser.add_argument("--time-limit", type=positive(float), default=1.0, metavar="S",
                        help="wall-clock limit per problem in seconds, for benchmarking "
                        "(default 1.0; the planner's own budget is in collision checks)")
    parser.add_argument("--planner", choices=PLANNERS, default="rrtconnect")
    parser.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    parser.add_argument("--step", type=positive(float), default=0.05, metavar="RAD",
                        help="largest joint move between two collision checks while planning "
                        "(default 0.05 rad)")
    parser.add_argument("--out", default=None, metavar="RESULTS.json",
                        help="write every problem's outcome and path (bt-manip schema "
                        "motion-bench)")
    parser.set_defaults(func=cmd_motion_bench)


VERB_ARGUMENTS = {"motion-bench": add_motion_bench_arguments}
"""The verbs of this module and the function that adds each one's arguments."""


def _progress(outcome: Outcome) -> None:
    if not outcome.solved:
        print(f"  {outcome.family}/{outcome.scene}: unsolved: {outcome.reason}")
    elif not outcome.valid:
        print(f"  {outcome.family}/{outcome.scene}: invalid: {outcome.reason}")


def cmd_motion_bench(args: argparse.Namespace) -> int:
    out = check_output_file("--out", args.out) if args.out else None
    folders = family_folders(Path(args.dir))
    robot = load_robot(Path(args.urdf), Path(args.srdf) if args.srdf else None, args.group)
    options = BenchOptions(planner=args.planner, time_limit_s=args.time_limit, seed=args.seed,
                           step=args.step)
    outcomes = run_bench(robot, folders, options, progress=_progress)
    for line in summary_lines(outcomes):
        print(line)
    if out is not None:
        write_text(out, json.dumps(results_document(robot, options, outcomes), indent=1) + "\n")
        print(f"wrote {out}")
    return 0
