"""``bt-manip bench``: run a bench (or a sweep of benches), stream its episodes, resume it.

Exit codes: 0 every episode succeeded; 1 some did not (the statistics are still written);
2 bad input (tree, world, options, a log that cannot be resumed), nothing run; 130
interrupted (Ctrl-C or SIGTERM): the episodes that finished are in ``episodes.jsonl``, and
``bt-manip bench --resume DIR`` runs the rest.
"""

from __future__ import annotations

import argparse
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from bt_manip.bench_log import (
    LOG_NAME,
    BenchHeader,
    BenchLog,
    check_unchanged,
    read_log,
)
from bt_manip.errors import InputError, Problem

if TYPE_CHECKING:
    from bt_manip.bench import BenchSummary, EpisodeResult
    from bt_manip.episode import EpisodeSpec

RESUME_KEEPS = ("jobs", "backend", "address", "btlog_failures", "resume")
"""The bench options that ``--resume`` takes from the command line; the others come from the
log."""
DEFINING: dict[str, Any] = {
    "tree": None, "world": None, "runs": 20, "seed": 0, "tree_id": None, "models": [], "bb": [],
    "max_ticks": None, "max_sim_time": 600.0, "tick_hz": 20.0, "inject": [], "imports": [],
    "sweep": None,
}
"""The options that define a bench, with their defaults (``--resume`` refuses them)."""


@dataclass
class Point:
    """One bench of the command: its folder, its episodes' spec and seeds, and what ran."""

    folder: Path
    spec: EpisodeSpec
    seeds: list[int]
    value: str = ""
    done: list[EpisodeResult] | None = None
    valid_bytes: int = 0


def _check_resume_args(args: argparse.Namespace) -> None:
    given = [name for name, default in DEFINING.items()
             if getattr(args, name, default) not in (default, None, [])]
    if given:
        flags = ", ".join("--" + g.replace("_", "-") if g not in ("tree",) else "TREE"
                          for g in given)
        raise InputError.single(
            "--resume", None, f"the bench's definition comes from {args.resume}/{LOG_NAME}; "
                              f"leave out {flags}")


def _resume_points(folder: Path) -> tuple[str | None, list[Point]]:
    from bt_manip.bench_sweep import PLAN_NAME, read_plan

    if (folder / PLAN_NAME).is_file() and not (folder / LOG_NAME).is_file():
        text, plan = read_plan(folder)
        points = []
        for value, sub in plan:
            p = _resumed(folder / sub)
            p.value = value
            points.append(p)
        return text, points
    return None, [_resumed(folder)]


def _resumed(folder: Path) -> Point:
    logged = read_log(folder)
    check_unchanged(logged, folder)
    return Point(folder, logged.spec, logged.header.seeds, done=logged.results,
                 valid_bytes=logged.valid_bytes)


def _new_points(args: argparse.Namespace, base: EpisodeSpec) -> tuple[str | None, list[Point]]:
    from bt_manip.bench_sweep import sweep_points, write_plan
    from bt_manip.outputs import make_folder

    out = Path(args.out)
    seeds = [args.seed + i for i in range(args.runs)]
    if not args.sweep:
        make_folder(out)
        return None, [Point(out, base, seeds)]
    swept = sweep_points(base, args.sweep)
    make_folder(out)
    write_plan(out, args.sweep, swept)
    points = []
    for sp in swept:
        make_folder(out / sp.folder)
        points.append(Point(out / sp.folder, sp.spec, seeds, value=sp.value))
    return args.sweep, points


def _btlog_folder(args: argparse.Namespace, point: Point, sweep: str | None) -> str | None:
    if not args.btlog_failures:
        return None
    if sweep is None:
        return str(args.btlog_failures)
    from bt_manip.outputs import make_folder

    make_folder(args.btlog_failures)
    return str(Path(args.btlog_failures) / point.folder.name)


def _run_point(args: argparse.Namespace, point: Point, sweep: str | None) -> BenchSummary:
    from bt_manip.bench import run_bench, summarise, write_outputs

    done = list(point.done or [])
    if point.done is None:
        log = BenchLog.create(point.folder, BenchHeader.of(point.spec, point.seeds))
    else:
        header = BenchHeader.of(point.spec, point.seeds)
        log = BenchLog.reopen(point.folder, header, point.valid_bytes)
    missing = [s for s in point.seeds if s not in {r.seed for r in done}]
    label = f" [{sweep} = {point.value}]" if sweep else ""
    first = point.seeds[0] if point.seeds else 0
    if done:
        print(f"bench{label}: {len(done)} of {len(point.seeds)} episodes already in "
              f"{point.folder / LOG_NAME}; running the other {len(missing)}")
    else:
        print(f"bench{label}: {len(point.seeds)} episodes of {point.spec.tree} on "
              f"{point.spec.world}, seeds {first}..{point.seeds[-1]}, "
              f"{_where(args)}")
    try:
        with log:
            new = run_bench(point.spec, len(missing), jobs=args.jobs, seeds=missing,
                            btlog_failures=_btlog_folder(args, point, sweep),
                            on_result=log.append, backend=args.backend, address=args.address)
    except KeyboardInterrupt:
        kept = _count_episodes(point.folder)
        print(f"interrupted: {kept} of {len(point.seeds)} episodes kept in "
              f"{point.folder / LOG_NAME}; continue with: bt-manip bench --resume "
              f"{args.resume or args.out}")
        raise
    results = sorted(done + new, key=lambda r: r.seed)
    summary = summarise(results, point.spec)
    summary.first_seed = first
    print(summary.text())
    try:
        write_outputs(results, summary, point.folder)
    except OSError as exc:
        raise InputError.single("--out", None, f"cannot write {point.folder}: "
                                f"{exc.strerror or exc}") from None
    print(f"wrote {point.folder}/{LOG_NAME}, episodes.json, episodes.csv, summary.json, "
          "outcomes.png")
    return summary


def _count_episodes(folder: Path) -> int:
    try:
        return len(read_log(folder).results)
    except InputError:
        return 0


def _where(args: argparse.Namespace) -> str:
    if args.backend == "ray":
        return f"on Ray ({args.address or 'a local instance'})"
    return f"{args.jobs} process(es)"


def run_bench_command(args: argparse.Namespace) -> int:
    """The ``bench`` verb (see the module docstring for its exit codes)."""
    from bt_manip.bench_sweep import write_results
    from bt_manip.episode import Episode
    from bt_manip.outputs import check_output_folder

    if args.btlog_failures:
        check_output_folder("--btlog-failures", args.btlog_failures)
    if args.resume:
        _check_resume_args(args)
        sweep, points = _resume_points(Path(args.resume))
    else:
        if not args.tree or not args.world:
            missing = [p for p, v in (("TREE", args.tree), ("--world", args.world)) if not v]
            raise InputError([Problem("bench", None, f"{' and '.join(missing)} required "
                                      "(or --resume DIR)")])
        check_output_folder("--out", args.out)
        from bt_manip.cli import episode_spec

        base = episode_spec(args)
        with Episode(base):  # check the tree and world once, before starting workers
            pass
        sweep, points = _new_points(args, base)
    summaries = []
    for point in points:
        summaries.append(_run_point(args, point, sweep))
    if sweep is not None:
        out = Path(args.resume or args.out)
        write_results(out, sweep, [(p.value, p.folder.name, s)
                                   for p, s in zip(points, summaries, strict=True)])
        print(f"sweep {sweep}:")
        for p, s in zip(points, summaries, strict=True):
            lo, hi = s.ci95
            print(f"  {p.value:>10}: {s.successes}/{s.runs} = {100 * s.success_rate:.1f} % "
                  f"({100 * lo:.1f}-{100 * hi:.1f} %)")
        print(f"wrote {out}/sweep.json, sweep.csv, sweep.png")
    if args.btlog_failures:
        failed = sum(s.runs - s.successes for s in summaries)
        print(f"wrote {failed} .btlog file(s) of failed episodes to {args.btlog_failures}")
    return 0 if all(s.successes == s.runs for s in summaries) else 1
