"""The benches one ``bt-manip bench`` runs: one, or one per value of a sweep; each a *point*.

A point is new (:func:`new_points`: its folder made, its seeds to run) or read back from the
episodes.jsonl of an interrupted bench (:func:`resume_points`). :func:`run_points` runs the
episodes each point still lacks, streams them to its log, prints and writes its statistics,
and for a sweep the sweep's own files.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from bt_manip.bench.coverage import (
    BenchCoverage,
    bench_coverage,
    coverage_info,
    tree_outline,
    write_coverage,
)
from bt_manip.bench.coverage_plot import write_coverage_png
from bt_manip.bench.episodes import EpisodeResult
from bt_manip.bench.files import write_outputs
from bt_manip.bench.log import LOG_NAME, BenchHeader, BenchLog, check_unchanged, read_log
from bt_manip.bench.pool import run_bench
from bt_manip.bench.stats import BenchSummary, summarise
from bt_manip.bench.sweep import PLAN_NAME, read_plan, sweep_points, write_plan, write_results
from bt_manip.episode import EpisodeSpec
from bt_manip.errors import InputError
from bt_manip.outputs import make_folder


@dataclass(frozen=True)
class PoolOptions:
    """Where and how a bench's episodes run; what ``--resume`` takes from the command line."""

    jobs: int = 1
    backend: str = "processes"
    address: str | None = None
    btlog_failures: str | None = None
    """Folder for a .btlog of each failed episode (a sub-folder per point of a sweep)."""
    folder: str = ""
    """The bench's output folder, named in the hint to resume it after an interruption."""

    def where(self) -> str:
        """Where the episodes run, for the first line a bench prints."""
        if self.backend == "ray":
            return f"on Ray ({self.address or 'a local instance'})"
        return f"{self.jobs} process(es)"


@dataclass
class Point:
    """One bench of the command: its folder, its episodes' spec and seeds, and what ran."""

    folder: Path
    spec: EpisodeSpec
    seeds: list[int]
    value: str = ""
    done: list[EpisodeResult] | None = None
    valid_bytes: int = 0
    results: list[EpisodeResult] | None = None
    """Every episode of the point, once it has run (:func:`run_point`)."""


def resume_points(folder: Path) -> tuple[str | None, list[Point]]:
    """The sweep text (None for a single bench) and the points of the bench in ``folder``,
    with the episodes each already has."""
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


def new_points(base: EpisodeSpec, seeds: list[int], out: Path,
               sweep: str | None) -> tuple[str | None, list[Point]]:
    """The points of a new bench of ``base`` (one per value of ``sweep`` when there is one),
    their folders made in ``out``."""
    if not sweep:
        make_folder(out)
        return None, [Point(out, base, seeds)]
    swept = sweep_points(base, sweep)
    make_folder(out)
    write_plan(out, sweep, swept)
    points = []
    for sp in swept:
        make_folder(out / sp.folder)
        points.append(Point(out / sp.folder, sp.spec, seeds, value=sp.value))
    return sweep, points


def _btlog_folder(options: PoolOptions, point: Point, sweep: str | None) -> str | None:
    if not options.btlog_failures:
        return None
    if sweep is None:
        return str(options.btlog_failures)
    make_folder(options.btlog_failures)
    return str(Path(options.btlog_failures) / point.folder.name)


def run_point(options: PoolOptions, point: Point, sweep: str | None) -> BenchSummary:
    """Run the episodes ``point`` lacks, appending each to its log as it finishes; print its
    statistics and write its files."""
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
              f"{options.where()}")
    try:
        with log:
            new = run_bench(point.spec, len(missing), jobs=options.jobs, seeds=missing,
                            btlog_failures=_btlog_folder(options, point, sweep),
                            on_result=log.append, backend=options.backend,
                            address=options.address)
    except KeyboardInterrupt:
        kept = _count_episodes(point.folder)
        print(f"interrupted: {kept} of {len(point.seeds)} episodes kept in "
              f"{point.folder / LOG_NAME}; continue with: bt-manip bench --resume "
              f"{options.folder}")
        raise
    results = sorted(done + new, key=lambda r: r.seed)
    point.results = results
    summary = summarise(results, point.spec)
    summary.first_seed = first
    print(summary.text())
    coverage = bench_coverage(tree_outline(point.spec), results, coverage_info(point.spec))
    print(coverage.text())
    try:
        write_outputs(results, summary, point.folder)
        _write_coverage(coverage, point.folder)
    except OSError as exc:
        raise InputError.single("--out", None, f"cannot write {point.folder}: "
                                f"{exc.strerror or exc}") from None
    print(f"wrote {point.folder}/{LOG_NAME}, episodes.json, episodes.csv, summary.json, "
          "outcomes.png, coverage.json, coverage.png")
    return summary


def _write_coverage(coverage: BenchCoverage, folder: Path) -> None:
    """coverage.json and coverage.png in ``folder``."""
    write_coverage(coverage, folder)
    write_coverage_png(coverage.to_json(), folder / "coverage.png")


def _sweep_coverage(points: list[Point], sweep: str, out: Path) -> None:
    """The sweep's coverage.json and coverage.png in ``out``: the episodes of every point
    summed (the same tree at every value; each point's episodes count apart)."""
    base = points[0].spec
    every = [r for point in points for r in point.results or []]
    info = {**coverage_info(base), "inject": [f.text() for f in base.inject], "sweep": sweep}
    merged = bench_coverage(tree_outline(base), every, info)
    print(f"sweep {merged.text()}")
    _write_coverage(merged, out)


def _count_episodes(folder: Path) -> int:
    try:
        return len(read_log(folder).results)
    except InputError:
        return 0


def run_points(options: PoolOptions, points: list[Point],
               sweep: str | None) -> list[BenchSummary]:
    """Run every point (:func:`run_point`); for a sweep, then write sweep.json, sweep.csv and
    sweep.png in ``options.folder`` and print the success rate at each value."""
    summaries = []
    for point in points:
        summaries.append(run_point(options, point, sweep))
    if sweep is not None:
        out = Path(options.folder)
        write_results(out, sweep, [(p.value, p.folder.name, s)
                                   for p, s in zip(points, summaries, strict=True)])
        print(f"sweep {sweep}:")
        for p, s in zip(points, summaries, strict=True):
            lo, hi = s.ci95
            print(f"  {p.value:>10}: {s.successes}/{s.runs} = {100 * s.success_rate:.1f} % "
                  f"({100 * lo:.1f}-{100 * hi:.1f} %)")
        _sweep_coverage(points, sweep, out)
        print(f"wrote {out}/sweep.json, sweep.csv, sweep.png, coverage.json, coverage.png")
    return summaries
