"""The run loop: tick the tree, step the world, stop on a result or a budget.

One :class:`Runner` owns a run. Each iteration ticks the tree once and then steps physics
``rate_hz / tick_hz`` times (240 Hz / 20 Hz = 12 steps by default). Nothing waits on the wall
clock unless pacing is asked for (``realtime``), so a headless run goes as fast as physics
allows. Without a world the tree runs on the monotonic clock and the loop paces itself at the
tick rate, as BehaviorTree.CPP's ``tickWhileRunning`` does.

The tree is ticked with ``tick()`` (BT.CPP's ``tickOnce()``: a wake-up signal re-ticks the root
within the same tick). A root that returns SKIPPED (every node it would run was skipped by a
pre-condition) ends the run with status SKIPPED.

A run ends with a :class:`~bt_manip.run.status.RunStatus` and its exit code
(:data:`~bt_manip.run.status.EXIT_CODES`): 0 root SUCCESS, 1 root FAILURE, root SKIPPED or
budget spent, 2 bad input (including a tree that breaks while running: a script error, a port
without a value), 130 interrupted. In every case but SUCCESS and FAILURE the tree is halted
first and the robots are left stopped. The runner owns its hooks (:mod:`bt_manip.run.hooks`):
it calls them after each tick and closes them when the run ends, however it ends.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Protocol

import py_trees

from bt_manip.bt.node import BtNode, TreeRuntimeError
from bt_manip.run.failure_cause import FailureCause, failure_cause
from bt_manip.run.hooks import RunHook, TickCallback, close_hooks
from bt_manip.run.jit_clock import JitClock
from bt_manip.run.node_counts import NodeCounter
from bt_manip.run.report import NodeReport, RunReport, cause_json, node_reports
from bt_manip.run.status import RunStatus

if TYPE_CHECKING:
    from bt_manip.sim.world import World

MAX_PACING_LAG = 0.25
"""Seconds a paced run may lag behind real time before the lag is forgotten."""
INTERRUPTED_REASON = "interrupted by the user"


class TickableTree(Protocol):
    """What the runner needs of a tree (``bt_manip.bt.Tree`` provides it)."""

    @property
    def root(self) -> BtNode | py_trees.behaviour.Behaviour: ...
    """The root node: a bt-manip node or a py_trees behaviour."""

    def tick(self) -> Any: ...
    """The root's status after the tick: a ``NodeStatus`` (or a py_trees ``Status``)."""

    def halt(self) -> None: ...


@dataclass(frozen=True)
class RunOptions:
    """How to run: tick rate, budgets and pacing (frozen: change a copy with
    :func:`dataclasses.replace`)."""

    tick_hz: float = 20.0
    max_sim_time: float | None = 600.0
    max_ticks: int | None = None
    realtime: float | None = None
    """Pace sim time to ``realtime`` x wall time (1.0 = real time); None runs flat out.

    A run that falls behind (paused on a Groot2 breakpoint, or a slow tick) goes on at the
    same pace from where it is, without rushing to catch up."""


class Runner:
    """Ticks a tree against a world (or the monotonic clock) until it ends or a budget is spent.

    Args:
        tree: anything with ``root``, ``tick()`` and ``halt()``.
        world: a :class:`bt_manip.sim.world.World`, or None for trees of built-ins only.
        options: tick rate, budgets, pacing.
        on_tick: the run's hooks (:class:`~bt_manip.run.hooks.RunHook`: live views, recorders)
            and plain callables, called after every tick with the runner. The runner owns
            them: :meth:`run` closes every hook when it ends (see :meth:`close_hooks`).
    """

    def __init__(
        self,
        tree: TickableTree,
        world: World | None = None,
        options: RunOptions | None = None,
        on_tick: Sequence[RunHook | TickCallback] = (),
        before_tick: Sequence[TickCallback] = (),
    ) -> None:
        self.tree = tree
        self.before_tick = list(before_tick)
        self.world = world
        self.options = options or RunOptions()
        self.on_tick = list(on_tick)
        self.ticks = 0
        self.counter: NodeCounter | None = None
        """Each node's ticks and results in the run (bt_manip trees; None otherwise)."""
        self.cause: FailureCause | None = None
        """The node whose failure ended the run (bt_manip trees; None otherwise)."""
        if world is not None:
            ratio = world.rate_hz / self.options.tick_hz
            self.steps_per_tick = max(1, round(ratio))
        else:
            self.steps_per_tick = 0
        self._start_sim = self._now()
        self._pace_wall0 = time.perf_counter()

    def _now(self) -> float:
        if self.world is not None:
            return self.world.time
        return time.monotonic()

    @property
    def sim_time(self) -> float:
        return self._now() - self._start_sim

    def run(self) -> RunReport:
        """Run to the end; Ctrl-C halts the tree and gives status INTERRUPTED. The hooks are
        closed when it returns or raises."""
        try:
            return self._run()
        finally:
            if self.counter is not None:
                self.counter.detach()
            self.close_hooks()

    def close_hooks(self) -> None:
        """Close every hook of the run, in order (idempotent: a hook closes once)."""
        close_hooks(self.on_tick)

    def _run(self) -> RunReport:
        opts = self.options
        wall0 = time.perf_counter()
        self._pace_wall0 = wall0
        self._start_sim = self._now()
        status, reason = RunStatus.BUDGET, ""
        counter = NodeCounter(self.tree).attach() if NodeCounter.can_watch(self.tree) else None
        self.counter = counter
        jit = JitClock()
        try:
            with jit:
                while True:
                    for sense in self.before_tick:
                        sense(self)
                    result = self.tree.tick().name
                    self.ticks += 1
                    for hook in self.on_tick:
                        hook(self)
                    if result == "SUCCESS":
                        status = RunStatus.SUCCESS
                        break
                    if result == "FAILURE":
                        status = RunStatus.FAILURE
                        reason = self._failure_reason()
                        break
                    if result == "SKIPPED":
                        status = RunStatus.SKIPPED
                        reason = "every node the root would run was skipped by a pre-condition"
                        break
                    if opts.max_ticks is not None and self.ticks >= opts.max_ticks:
                        reason = f"tick budget of {opts.max_ticks} spent"
                        break
                    if opts.max_sim_time is not None and self.sim_time >= opts.max_sim_time:
                        reason = f"time budget of {opts.max_sim_time:g} s spent"
                        break
                    self._advance()
        except KeyboardInterrupt:
            status, reason = RunStatus.INTERRUPTED, INTERRUPTED_REASON
        except SystemError as exc:
            # a Ctrl-C that came while compiled code ran (the numba pose search): Python
            # reports it as a SystemError caused by the KeyboardInterrupt
            if not isinstance(exc.__cause__, KeyboardInterrupt):
                raise
            status, reason = RunStatus.INTERRUPTED, INTERRUPTED_REASON
        except TreeRuntimeError as exc:
            status, reason = RunStatus.ERROR, str(exc)
        if status in (RunStatus.BUDGET, RunStatus.INTERRUPTED, RunStatus.ERROR):
            try:
                self.tree.halt()
            except TreeRuntimeError as exc:  # an _onHalted script failed
                if status is not RunStatus.ERROR:
                    status, reason = RunStatus.ERROR, str(exc)
            self._make_safe()
        wall = time.perf_counter() - wall0
        return RunReport(
            status=status,
            reason=reason,
            sim_time=self.sim_time,
            wall_time=wall,
            jit_time=jit.seconds,
            ticks=self.ticks,
            nodes=self._records(),
            cause=cause_json(self.cause),
        )

    def _advance(self) -> None:
        opts = self.options
        if self.world is not None:
            self.world.step(self.steps_per_tick)
            if opts.realtime:
                ahead = self.sim_time / opts.realtime - (time.perf_counter() - self._pace_wall0)
                if ahead > 0:
                    time.sleep(ahead)
                elif ahead < -MAX_PACING_LAG:
                    self._pace_wall0 -= ahead  # forget the lag: no catching up
        else:
            time.sleep(1.0 / opts.tick_hz)

    def _records(self) -> list[NodeReport]:
        return node_reports(self.tree, self.counter)

    def _failure_reason(self) -> str:
        """The reason of the failure that ended the run (see
        :mod:`bt_manip.run.failure_cause`): what the user needs to read first."""
        if callable(getattr(self.tree, "walk", None)):
            self.cause = failure_cause(self.tree)
            return self.cause.text() if self.cause is not None else ""
        failed = [
            r for r in self._records() if "FAILURE" in (r.status, r.last_status) and r.reason
        ]
        if not failed:
            return ""
        deepest = max(failed, key=lambda r: r.path.count("/"))
        return f"{deepest.path}: {deepest.reason}"

    def _make_safe(self) -> None:
        """Leave every robot stopped and holding its arm after a halt."""
        if self.world is None:
            return
        for robot in self.world.robots.values():
            robot.stop_base()
            robot.hold_arm()
