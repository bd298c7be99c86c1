"""Running a bench's episodes: in this process, in spawned worker processes, or on Ray.

:func:`run_bench` runs one episode per seed and hands each result back as it finishes, with a
progress bar (or progress lines) on stderr. Worker processes never take a Ctrl-C: the main
process stops them.
"""

from __future__ import annotations

import os
import queue
import signal
import sys
import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import replace
from multiprocessing import get_context, resource_tracker
from pathlib import Path
from typing import TYPE_CHECKING, Any

from bt_manip.bench.episodes import EpisodeResult, run_one
from bt_manip.bench.ray import run_on_ray
from bt_manip.outputs import make_folder

if TYPE_CHECKING:
    from bt_manip.episode import EpisodeSpec


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
    (a local one when None), see :mod:`bt_manip.bench.ray`.
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
