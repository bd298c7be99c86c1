"""Monte-Carlo runs of a tree: many seeded episodes in parallel, with statistics.

``bt-manip bench TREE --world W --runs N --seed S [--inject ...] [--jobs J] [--out DIR]`` runs
episodes with seeds S, S+1, ..., S+N-1 (each seed draws the world's randomised starts and the
injected faults), in J worker processes, and reports:

- the success rate with a 95 % Wilson score interval;
- sim time, wall time (building the world and loading the tree included) and real-time factor
  per episode (mean, median, 95th percentile);
- failures counted by node and reason (the node whose failure ended each failed episode);
- the actions that failed during episodes, and in how many episodes: the failures the tree
  recovered from (or did not), for instance how often a recovery branch was needed
  (conditions are left out: their failures are how a tree decides, not trouble).

It writes ``episodes.json``, ``episodes.csv``, ``summary.json`` and ``outcomes.png`` to DIR.
"""

from __future__ import annotations

import csv
import json
import math
import os
import queue
import signal
import sys
import threading
import time
from collections import Counter
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import asdict, dataclass, field, replace
from multiprocessing import get_context, resource_tracker
from pathlib import Path
from typing import Any

import numpy as np

from bt_manip.bench_log import SCHEMA_VERSION
from bt_manip.episode import Episode, EpisodeSpec
from bt_manip.outputs import make_folder


@dataclass
class EpisodeResult:
    """The outcome of one episode, small enough to send between processes."""

    seed: int
    status: str
    reason: str
    sim_time: float
    wall_time: float
    ticks: int
    failed_node: str = ""
    """On FAILURE, the node whose failure ended the episode: ``name (ID)``, or its ID."""
    injected: list[dict[str, Any]] = field(default_factory=list)
    metrics: dict[str, float] = field(default_factory=dict)
    """Numeric entries of the root blackboard at the end (counters a tree keeps)."""
    leaf_failures: dict[str, int] = field(default_factory=dict)
    """Per action node (by path), how many times it failed during the episode."""

    @property
    def success(self) -> bool:
        return self.status == "SUCCESS"


def wilson_interval(successes: int, n: int, z: float = 1.959964) -> tuple[float, float]:
    """95 % Wilson score interval of a binomial proportion (0..1)."""
    if n == 0:
        return (0.0, 1.0)
    p = successes / n
    denom = 1 + z * z / n
    centre = (p + z * z / (2 * n)) / denom
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / denom
    return (max(0.0, centre - half), min(1.0, centre + half))


def run_one(spec: EpisodeSpec) -> EpisodeResult:
    """Run one episode (in a worker process) and condense its report.

    The wall time counts the whole episode, building its world and loading its tree included
    (the run report's own wall time counts the ticks only).

    With ``spec.btlog`` set, the episode's .btlog is kept only when it did not succeed."""
    wall0 = time.perf_counter()
    with Episode(spec) as episode:
        leaf_failures = count_leaf_failures(episode.tree)
        report = episode.run()
        metrics = {
            k: float(v)
            for k, v in episode.tree.blackboard.as_dict().items()
            if isinstance(v, int | float) and not isinstance(v, bool)
        }
    wall_time = time.perf_counter() - wall0
    if report.status == "INTERRUPTED":  # Ctrl-C while the episode ran: the runner halted the
        raise KeyboardInterrupt         # tree; the bench stops, this episode did not finish
    if spec.btlog and report.status == "SUCCESS":
        Path(spec.btlog).unlink(missing_ok=True)
    failed_node = ""
    if report.status == "FAILURE" and report.cause:
        name, node_id = report.cause["name"], report.cause["node"]
        failed_node = node_id if name == node_id else f"{name} ({node_id})"
    return EpisodeResult(
        seed=spec.seed,
        status=report.status,
        reason=report.reason,
        sim_time=report.sim_time,
        wall_time=wall_time,
        ticks=report.ticks,
        failed_node=failed_node,
        injected=list(report.extra.get("injected", [])),
        metrics=metrics,
        leaf_failures=dict(leaf_failures),
    )


def count_leaf_failures(tree: Any) -> Counter[str]:
    """A counter, kept up to date while ``tree`` runs, of the times each action node (a leaf
    that is not a condition, by its path) goes to FAILURE."""
    from bt_manip.bt.status import NodeStatus
    from bt_manip.bt.walk import children_of, walk_nodes
    from bt_manip.groot.monitor import watch

    counts: Counter[str] = Counter()
    for walked in walk_nodes(tree.root):
        if children_of(walked.node) or getattr(walked.node, "KIND", "Action") == "Condition":
            continue

        def changed(node: Any, previous: Any, new: Any, path: str = walked.path) -> None:
            if new is NodeStatus.FAILURE:
                counts[path] += 1

        watch(walked.node, changed)
    return counts


@dataclass
class BenchSummary:
    """Statistics over all episodes."""

    runs: int
    successes: int
    success_rate: float
    ci95: tuple[float, float]
    sim_time: dict[str, float]
    wall_time: dict[str, float]
    real_time_factor: dict[str, float]
    failures: list[dict[str, Any]]
    injected: dict[str, int]
    metrics: dict[str, dict[str, float]] = field(default_factory=dict)
    leaf_failures: list[dict[str, Any]] = field(default_factory=list)
    """Per action that failed in some episode: its path, the episodes it failed in, the
    times."""
    tree: str = ""
    world: str = ""
    first_seed: int = 0
    inject: list[str] = field(default_factory=list)

    def text(self) -> str:
        lo, hi = self.ci95
        lines = [
            f"success: {self.successes}/{self.runs} = {self.success_rate * 100:.1f} % "
            f"(95 % interval {lo * 100:.1f}-{hi * 100:.1f} %)",
            f"sim time per episode: mean {self.sim_time['mean']:.1f} s, median "
            f"{self.sim_time['median']:.1f} s, p95 {self.sim_time['p95']:.1f} s",
            f"wall time per episode: mean {self.wall_time['mean']:.2f} s, median "
            f"{self.wall_time['median']:.2f} s; real-time factor median "
            f"{self.real_time_factor['median']:.1f}x",
        ]
        for name, st in sorted(self.metrics.items()):
            lines.append(
                f"blackboard {name}: mean {st['mean']:g}, min {st['min']:g}, max {st['max']:g}"
            )
        if self.injected:
            lines.append(
                "faults injected: "
                + ", ".join(f"{k} x{v}" for k, v in sorted(self.injected.items()))
            )
        for f in self.failures:
            lines.append(f"  {f['count']:3d} x {f['node'] or '-'}: {f['reason']}")
        if self.leaf_failures:
            lines.append("actions that failed (episodes, times):")
            for f in self.leaf_failures[:LEAVES_SHOWN]:
                lines.append(f"  {f['episodes']:3d} {f['times']:4d}  {f['path']}")
            if len(self.leaf_failures) > LEAVES_SHOWN:
                lines.append(f"  ... {len(self.leaf_failures) - LEAVES_SHOWN} more in "
                             "summary.json")
        return "\n".join(lines)


LEAVES_SHOWN = 12
"""Leaves listed in the text summary (summary.json has them all)."""


def _stats(values: list[float]) -> dict[str, float]:
    if not values:
        return {"mean": 0.0, "median": 0.0, "p95": 0.0, "min": 0.0, "max": 0.0}
    a = np.asarray(values, dtype=float)
    return {
        "mean": float(a.mean()),
        "median": float(np.median(a)),
        "p95": float(np.percentile(a, 95)),
        "min": float(a.min()),
        "max": float(a.max()),
    }


def summarise(results: list[EpisodeResult], base: EpisodeSpec) -> BenchSummary:
    n = len(results)
    wins = sum(r.success for r in results)
    failures = Counter((r.failed_node, r.reason) for r in results if not r.success)
    injected = Counter(e["kind"] for r in results for e in r.injected)
    rtf = [r.sim_time / r.wall_time for r in results if r.wall_time > 0]
    names = sorted({k for r in results for k in r.metrics})
    metrics = {k: _stats([r.metrics[k] for r in results if k in r.metrics]) for k in names}
    episodes: Counter[str] = Counter(p for r in results for p in r.leaf_failures)
    times: Counter[str] = Counter()
    for r in results:
        times.update(r.leaf_failures)
    leaves = [{"path": p, "episodes": c, "times": times[p]}
              for p, c in sorted(episodes.items(), key=lambda kv: (-kv[1], -times[kv[0]]))]
    return BenchSummary(
        runs=n,
        successes=wins,
        success_rate=wins / n if n else 0.0,
        ci95=wilson_interval(wins, n),
        sim_time=_stats([r.sim_time for r in results]),
        wall_time=_stats([r.wall_time for r in results]),
        real_time_factor=_stats(rtf),
        failures=[{"node": k[0], "reason": k[1], "count": c} for k, c in failures.most_common()],
        injected=dict(injected),
        metrics=metrics,
        leaf_failures=leaves,
        tree=base.tree,
        world=base.world or "",
        first_seed=base.seed,
        inject=[f.text() for f in base.inject],
    )


def _progress(total: int) -> Callable[[EpisodeResult], None]:
    """Progress of a bench: in a terminal a bar with the running success rate, the time spent
    and the time left; otherwise a line every 10 %."""
    done = {"n": 0, "ok": 0}

    def rate() -> str:
        return f"{done['ok']}/{done['n']} succeeded ({100.0 * done['ok'] / done['n']:.0f} %)"

    if sys.stderr.isatty():
        from rich.progress import (
            BarColumn,
            MofNCompleteColumn,
            Progress,
            TextColumn,
            TimeElapsedColumn,
            TimeRemainingColumn,
        )

        bar = Progress(
            TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(),
            TextColumn("elapsed"), TimeElapsedColumn(), TextColumn("left"),
            TimeRemainingColumn(), transient=True,
        )
        bar.start()
        task = bar.add_task("episodes", total=total)

        def tick(r: EpisodeResult) -> None:
            done["n"] += 1
            done["ok"] += r.success
            bar.update(task, advance=1, description=rate())
            if done["n"] == total:
                bar.stop()

        return tick
    step = max(1, total // 10)

    def log(r: EpisodeResult) -> None:
        done["n"] += 1
        done["ok"] += r.success
        if done["n"] % step == 0 or done["n"] == total:
            print(f"  {done['n']}/{total} episodes, {rate()}", file=sys.stderr)

    return log


@contextmanager
def _ctrl_c_held() -> Iterator[None]:
    """Hold Ctrl-C (SIGINT) back while the body runs; one that comes meanwhile is delivered
    (as KeyboardInterrupt) when it ends. Processes started in the body inherit the block, so
    they never take a Ctrl-C: the main process stops them."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    # multiprocessing's resource tracker unblocks SIGINT when it starts: start it first
    resource_tracker.ensure_running()
    mask = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, mask)


def _worker_started(started: Any) -> None:
    started.put(os.getpid())


def _start_workers(jobs: int, wait: float = 20.0) -> Any:
    """A pool of ``jobs`` spawned workers, returned once each has started (or after ``wait``
    seconds), so that stopping them never meets one half-way through its start-up."""
    context = get_context("spawn")
    started = context.Queue()
    pool = context.Pool(jobs, initializer=_worker_started, initargs=(started,))
    try:
        for _ in range(jobs):
            started.get(timeout=wait)
    except queue.Empty:
        pass
    return pool


def episode_specs(base: EpisodeSpec, seeds: list[int],
                  btlog_failures: str | None = None) -> list[EpisodeSpec]:
    """One spec per seed; with ``btlog_failures``, each keeps ``seed-N.btlog`` there when its
    episode does not succeed (the folder is made here)."""
    specs = [replace(base, seed=seed) for seed in seeds]
    if btlog_failures:
        make_folder(btlog_failures)
        specs = [replace(s, btlog=str(Path(btlog_failures) / f"seed-{s.seed}.btlog"))
                 for s in specs]
    return specs


def run_bench(
    base: EpisodeSpec,
    runs: int,
    jobs: int = 1,
    btlog_failures: str | None = None,
    seeds: list[int] | None = None,
    on_result: Callable[[EpisodeResult], None] | None = None,
    backend: str = "processes",
    address: str | None = None,
) -> list[EpisodeResult]:
    """Run ``runs`` episodes with seeds base.seed + i (or the given ``seeds``); results sorted
    by seed. ``on_result`` is called with each result as its episode finishes (in the main
    process), before the next one is taken.

    With ``btlog_failures`` (a folder whose parent exists), each episode that does not succeed
    leaves ``seed-N.btlog`` there, to replay in Groot2.

    ``backend`` "processes": with ``jobs`` > 1 the episodes run in spawned worker processes
    (each builds its own PyBullet world). The workers never take a Ctrl-C (one interrupted
    while it starts up would print a traceback); a Ctrl-C, or an error, in the main process
    stops them. ``backend`` "ray": the episodes are Ray tasks on the cluster at ``address``
    (a local one when None), see :mod:`bt_manip.bench_ray`.
    """
    if seeds is None:
        seeds = [base.seed + i for i in range(runs)]
    specs = episode_specs(base, seeds, btlog_failures)
    results: list[EpisodeResult] = []
    progress = _progress(len(specs))

    def finished(result: EpisodeResult) -> None:
        results.append(result)
        if on_result is not None:
            on_result(result)
        progress(result)

    if backend == "ray":
        from bt_manip.bench_ray import run_on_ray

        run_on_ray(specs, finished, address=address, jobs=jobs)
    elif jobs <= 1 or len(specs) <= 1:
        for spec in specs:
            finished(run_one(spec))
    else:
        _run_in_pool(specs, jobs, finished)
    return sorted(results, key=lambda r: r.seed)


def _run_in_pool(specs: list[EpisodeSpec], jobs: int,
                 finished: Callable[[EpisodeResult], None]) -> None:
    pool = None
    try:
        with _ctrl_c_held():  # before any other thread starts, so that none takes a Ctrl-C
            pool = _start_workers(min(jobs, len(specs)))
        for result in pool.imap_unordered(run_one, specs):
            finished(result)
    except BaseException:
        if pool is not None:
            pool.terminate()
        raise
    else:
        pool.close()
    finally:
        if pool is not None:
            pool.join()


def write_outputs(results: list[EpisodeResult], summary: BenchSummary, out: Path) -> None:
    """episodes.json, episodes.csv, summary.json and outcomes.png in ``out``."""
    make_folder(out)
    episodes = {"schema_version": SCHEMA_VERSION, "episodes": [asdict(r) for r in results]}
    (out / "episodes.json").write_text(json.dumps(episodes, indent=2) + "\n")
    names = sorted({k for r in results for k in r.metrics})
    with open(out / "episodes.csv", "w", newline="") as fh:
        w = csv.writer(fh)
        head = ["schema_version", "seed", "status", "sim_time", "wall_time", "ticks",
                "failed_node", "reason"]
        w.writerow([*head, "injected", *names])
        for r in results:
            row = [SCHEMA_VERSION, r.seed, r.status, f"{r.sim_time:.3f}", f"{r.wall_time:.3f}",
                   r.ticks]
            row += [r.failed_node, r.reason, len(r.injected)]
            w.writerow(row + [r.metrics.get(k, "") for k in names])
    summary_json = {"schema_version": SCHEMA_VERSION, **asdict(summary)}
    (out / "summary.json").write_text(json.dumps(summary_json, indent=2) + "\n")
    _plot(results, summary, out / "outcomes.png")


STATUS_COLOURS = {
    "SUCCESS": "tab:green",
    "FAILURE": "tab:red",
    "BUDGET": "tab:orange",
    "SKIPPED": "tab:olive",
    "ERROR": "tab:purple",
    "INTERRUPTED": "tab:grey",
}


def _plot(results: list[EpisodeResult], summary: BenchSummary, path: Path) -> None:
    """Write :func:`outcomes_figure` to ``path`` (PNG)."""
    import matplotlib.pyplot as plt

    fig = outcomes_figure(results, summary)
    fig.savefig(path, dpi=90)
    plt.close(fig)


def outcomes_figure(results: list[EpisodeResult], summary: BenchSummary) -> Any:
    """The figure of outcomes.png: sim time per seed (left, coloured by outcome) and a
    histogram of the sim time per episode (right, stacked by outcome); integer ticks on the
    seed and count axes."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.ticker import MaxNLocator

    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(11, 4))
    statuses = [s for s in STATUS_COLOURS if any(r.status == s for r in results)]
    statuses += sorted({r.status for r in results} - set(statuses))
    colours = [STATUS_COLOURS.get(s, "black") for s in statuses]
    for status, colour in zip(statuses, colours, strict=True):
        pts = [(r.seed, r.sim_time) for r in results if r.status == status]
        xs, ys = zip(*pts, strict=True)
        ax1.scatter(xs, ys, c=colour, label=f"{status} ({len(pts)})", s=18)
    ax1.xaxis.set_major_locator(MaxNLocator(integer=True))
    ax1.set_xlabel("seed")
    ax1.set_ylabel("sim time (s)")
    lo, hi = summary.ci95
    ax1.set_title(
        f"success {summary.success_rate * 100:.1f} % (95 % CI {lo * 100:.0f}-{hi * 100:.0f} %)"
    )
    if statuses:
        ax1.legend(fontsize=8)
        ax2.hist(
            [[r.sim_time for r in results if r.status == s] for s in statuses],
            bins=min(20, max(5, len(results) // 2)),
            color=colours,
            stacked=True,
            label=statuses,
        )
    ax2.yaxis.set_major_locator(MaxNLocator(integer=True))
    ax2.set_xlabel("sim time per episode (s)")
    ax2.set_ylabel("episodes")
    ax2.set_title(f"histogram of sim time per episode ({summary.runs} episodes)")
    rtf = summary.real_time_factor["median"]
    fig.suptitle(
        f"{Path(summary.tree).name} on {Path(summary.world).name or 'no world'} "
        f"(median real-time factor {rtf:.1f}x)"
    )
    fig.tight_layout()
    return fig
