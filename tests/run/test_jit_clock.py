"""The part of a run's wall time numba spent compiling: timed while the clock runs, not
outside it, reported in the JSON and named in the summary when it is worth it."""

from __future__ import annotations

import time
from collections.abc import Callable

import numba
import pytest

from bt_manip.bt.status import NodeStatus
from bt_manip.run.jit_clock import JIT_NOTE_S, JitClock
from bt_manip.run.report import RunReport
from bt_manip.run.runner import Runner, RunOptions
from bt_manip.run.status import RunStatus


def _fresh_kernel() -> Callable[[float], float]:
    """A kernel numba has never compiled (not cached: it must compile in this process)."""

    @numba.njit(cache=False)
    def twice(x: float) -> float:
        return 2.0 * x

    return twice


def test_a_compile_inside_the_block_is_timed_one_outside_is_not() -> None:
    outside = _fresh_kernel()
    outside(1.0)
    with JitClock() as clock:
        time.sleep(0.05)  # not compiling: not counted
        before = clock.seconds
        t0 = time.perf_counter()
        assert _fresh_kernel()(2.0) == 4.0
        took = time.perf_counter() - t0
    assert before == 0.0
    assert 0.0 < clock.seconds <= took
    after = clock.seconds
    _fresh_kernel()(3.0)  # the clock is stopped
    assert clock.seconds == after


def test_a_run_reports_its_compile_time_and_a_summary_names_a_long_one() -> None:
    kernel = _fresh_kernel()

    class Compiles:
        """A tree whose first tick compiles a kernel and succeeds."""

        root = None

        def tick(self) -> NodeStatus:
            kernel(1.0)
            return NodeStatus.SUCCESS

        def halt(self) -> None:
            pass

    report = Runner(Compiles(), options=RunOptions(max_ticks=3)).run()
    assert report.status is RunStatus.SUCCESS
    assert 0.0 < report.jit_time <= report.wall_time
    assert report.to_json()["jit_time"] == report.jit_time

    long = RunReport(status=RunStatus.SUCCESS, reason="", sim_time=23.3, wall_time=29.7,
                     ticks=467, jit_time=24.25)
    assert long.summary().splitlines()[2] == (
        "  of which 24.2 s compiling bt-manip's kernels, once after an install (later runs "
        "load them from numba's cache)")
    short = RunReport(status=RunStatus.SUCCESS, reason="", sim_time=23.3, wall_time=2.1,
                      ticks=467, jit_time=JIT_NOTE_S / 10)
    assert len(short.summary().splitlines()) == 2


@pytest.mark.parametrize("seconds", [0.0, JIT_NOTE_S - 1e-9])
def test_no_mention_below_the_threshold(seconds: float) -> None:
    report = RunReport(status=RunStatus.SUCCESS, reason="", sim_time=1.0, wall_time=1.0,
                       ticks=1, jit_time=seconds)
    assert "compiling" not in report.summary()
