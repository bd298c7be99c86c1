"""The run loop: tick the tree, step the world, stop on a result or a budget, report.

One :class:`Runner` owns a run. Each iteration ticks the tree once and then steps physics
``rate_hz / tick_hz`` times (240 Hz / 20 Hz = 12 steps by default). Nothing waits on the wall
clock unless pacing is asked for (``realtime``), so a headless run goes as fast as physics
allows. Without a world the tree runs on the monotonic clock and the loop paces itself at the
tick rate, as BehaviorTree.CPP's ``tickWhileRunning`` does.

The tree is ticked with ``tick()`` (BT.CPP's ``tickOnce()``: a wake-up signal re-ticks the root
within the same tick). A root that returns SKIPPED (every node it would run was skipped by a
pre-condition) ends the run with status SKIPPED.

Exit codes (:data:`EXIT_CODES`): 0 root SUCCESS, 1 root FAILURE, root SKIPPED or budget spent,
2 bad input
(including a tree that breaks while running: a script error, a port without a value), 130
interrupted. In every case but SUCCESS and FAILURE the tree is halted first and the robots are
left stopped.
"""

from __future__ import annotations

import json
import math
import time
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any, Protocol, cast

import py_trees

from bt_manip.bt.node import BtNode, TreeRuntimeError
from bt_manip.bt.status import as_status
from bt_manip.bt.walk import walk_nodes
from bt_manip.failure_cause import FailureCause
from bt_manip.outputs import write_text

EXIT_SUCCESS = 0
EXIT_FAILURE = 1
EXIT_BAD_INPUT = 2
EXIT_INTERRUPTED = 130
MAX_PACING_LAG = 0.25
"""Seconds a paced run may lag behind real time before the lag is forgotten."""
EXIT_CODES = {
    "SUCCESS": EXIT_SUCCESS,
    "FAILURE": EXIT_FAILURE,
    "SKIPPED": EXIT_FAILURE,
    "BUDGET": EXIT_FAILURE,
    "ERROR": EXIT_BAD_INPUT,
    "INTERRUPTED": EXIT_INTERRUPTED,
}


class TickableTree(Protocol):
    """What the runner needs of a tree (``bt_manip.bt.Tree`` provides it)."""

    @property
    def root(self) -> BtNode | py_trees.behaviour.Behaviour: ...
    """The root node: a bt-manip node or a py_trees behaviour."""

    def tick(self) -> Any: ...
    """The root's status after the tick: a ``NodeStatus`` (or a py_trees ``Status``)."""

    def halt(self) -> None: ...


@dataclass
class RunOptions:
    """How to run: tick rate, budgets and pacing."""

    tick_hz: float = 20.0
    max_sim_time: float | None = 600.0
    max_ticks: int | None = None
    realtime: float | None = None
    """Pace sim time to ``realtime`` x wall time (1.0 = real time); None runs flat out.

    A run that falls behind (paused on a Groot2 breakpoint, or a slow tick) goes on at the
    same pace from where it is, without rushing to catch up."""


REPORT_SCHEMA_VERSION = 1
"""Version of the run report's JSON format (``--report``); bumped when a field changes meaning
or goes away."""


@dataclass
class NodeReport:
    """A node's final state for the report: ``status`` now (finished nodes are IDLE again, as
    in BehaviorTree.CPP) and ``last_status``, what it last returned."""

    path: str
    node: str
    status: str
    reason: str = ""
    last_status: str = ""


@dataclass
class RunReport:
    """What happened in a run; written as JSON by ``--report`` (with ``schema_version``
    :data:`REPORT_SCHEMA_VERSION`, documented by docs/schemas/run-report.schema.json)."""

    status: str
    reason: str
    sim_time: float
    wall_time: float
    ticks: int
    tree: str = ""
    world: str = ""
    seed: int | None = None
    nodes: list[NodeReport] = field(default_factory=list)
    extra: dict[str, Any] = field(default_factory=dict)
    cause: dict[str, str] = field(default_factory=dict)
    """On FAILURE, the node whose failure ended the run: ``path``, ``name``, ``node`` (its ID)
    and ``reason``; empty otherwise."""
    as_built: list[dict[str, Any]] | None = None
    """In a world written by ``bt-manip bim``: each scheduled element's planned and placed pose,
    deviation and status (:mod:`bt_manip.bim.as_built`); None elsewhere."""

    @property
    def exit_code(self) -> int:
        return EXIT_CODES[self.status]

    @property
    def real_time_factor(self) -> float:
        return self.sim_time / self.wall_time if self.wall_time > 0 else math.inf

    def to_json(self) -> dict[str, Any]:
        data = {"schema_version": REPORT_SCHEMA_VERSION, **asdict(self)}
        data["real_time_factor"] = (
            round(self.real_time_factor, 3) if math.isfinite(self.real_time_factor) else None
        )
        data["exit_code"] = self.exit_code
        if self.as_built is None:
            del data["as_built"]
        return data

    def write(self, path: str | Path) -> None:
        write_text(path, json.dumps(self.to_json(), indent=2) + "\n")

    def summary(self) -> str:
        rtf = self.real_time_factor
        rtf_text = f"{rtf:.1f}x real time" if math.isfinite(rtf) else "instant"
        lines = [
            f"result: {self.status}" + (f" ({self.reason})" if self.reason else ""),
            f"  sim time {self.sim_time:.2f} s, wall time {self.wall_time:.2f} s "
            f"({rtf_text}), {self.ticks} ticks",
        ]
        cause = self.cause.get("path")
        failed = [n for n in self.nodes if "FAILURE" in (n.status, n.last_status) and n.reason]
        failed.sort(key=lambda n: n.path != cause)  # the failure that ended the run first
        for n in failed[:10]:
            ended = " (ended the run)" if n.path == cause else ""
            lines.append(f"  FAILURE {n.path} [{n.node}]: {n.reason}{ended}")
        if self.as_built is not None:
            from bt_manip.bim.as_built import table_text

            lines.append(table_text(self.as_built))
        return "\n".join(lines)


def _cause_json(cause: FailureCause | None) -> dict[str, str]:
    if cause is None:
        return {}
    return {"path": cause.path, "name": cause.name, "node": cause.node_id, "reason": cause.reason}


def _as_built(world: Any) -> list[dict[str, Any]] | None:
    """The as-built table when ``world`` was written by ``bt-manip bim`` (see
    :mod:`bt_manip.bim.as_built`)."""
    if world is None or getattr(world, "path", None) is None:
        return None
    from bt_manip.bim.as_built import as_built, schedule_for

    schedule = schedule_for(world.path)
    return as_built(world, schedule) if schedule is not None else None


def node_reports(tree: Any) -> list[NodeReport]:
    """Every node of ``tree`` (a bt-manip tree or anything with a py_trees ``root``) with its
    status and feedback, in the order and with the paths of :func:`bt_manip.bt.walk.walk_nodes`.
    """
    root = getattr(tree, "root", None)
    if root is None:
        return []
    out: list[NodeReport] = []
    for walked in walk_nodes(root):
        node = walked.node
        if isinstance(node, BtNode):
            status, last = node.bt_status.value, node.last_status.value
        else:
            status = last = as_status(node.status).value
        out.append(NodeReport(walked.path, walked.node_id, status,
                              node.feedback_message or "", last))
    return out


class Runner:
    """Ticks a tree against a world (or the monotonic clock) until it ends or a budget is spent.

    Args:
        tree: anything with ``root``, ``tick()`` and ``halt()``.
        world: a :class:`bt_manip.sim.world.World`, or None for trees of built-ins only.
        options: tick rate, budgets, pacing.
        on_tick: callables run after every tick with the runner (live views, recorders).
    """

    def __init__(
        self,
        tree: TickableTree,
        world: Any = None,
        options: RunOptions | None = None,
        on_tick: Sequence[Callable[[Runner], None]] = (),
    ) -> None:
        self.tree = tree
        self.world = world
        self.options = options or RunOptions()
        self.on_tick = list(on_tick)
        self.ticks = 0
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
            return cast(float, self.world.time)
        return time.monotonic()

    @property
    def sim_time(self) -> float:
        return self._now() - self._start_sim

    def run(self) -> RunReport:
        """Run to the end; Ctrl-C halts the tree and gives status INTERRUPTED."""
        opts = self.options
        wall0 = time.perf_counter()
        self._pace_wall0 = wall0
        self._start_sim = self._now()
        status, reason = "BUDGET", ""
        try:
            while True:
                result = self.tree.tick().name
                self.ticks += 1
                for hook in self.on_tick:
                    hook(self)
                if result == "SUCCESS":
                    status = "SUCCESS"
                    break
                if result == "FAILURE":
                    status = "FAILURE"
                    reason = self._failure_reason()
                    break
                if result == "SKIPPED":
                    status = "SKIPPED"
                    reason = "every node the root would run was skipped by a pre-condition"
                    break
                if opts.max_ticks is not None and self.ticks >= opts.max_ticks:
                    reason = f"tick budget of {opts.max_ticks} spent"
                    break
                if opts.max_sim_time is not None and self.sim_time >= opts.max_sim_time:
                    reason = f"time budget of {opts.max_sim_time:g} s spent"
                    break
                self._advance(wall0)
        except KeyboardInterrupt:
            status, reason = "INTERRUPTED", "interrupted by the user"
        except SystemError as exc:
            # a Ctrl-C that came while compiled code ran (the numba pose search): Python
            # reports it as a SystemError caused by the KeyboardInterrupt
            if not isinstance(exc.__cause__, KeyboardInterrupt):
                raise
            status, reason = "INTERRUPTED", "interrupted by the user"
        except TreeRuntimeError as exc:
            status, reason = "ERROR", str(exc)
        if status in ("BUDGET", "INTERRUPTED", "ERROR"):
            try:
                self.tree.halt()
            except TreeRuntimeError as exc:  # an _onHalted script failed
                if status != "ERROR":
                    status, reason = "ERROR", str(exc)
            self._make_safe()
        wall = time.perf_counter() - wall0
        return RunReport(
            status=status,
            reason=reason,
            sim_time=self.sim_time,
            wall_time=wall,
            ticks=self.ticks,
            nodes=self._records(),
            cause=_cause_json(self.cause),
            as_built=_as_built(self.world),
        )

    def _advance(self, wall0: float) -> None:
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
        return node_reports(self.tree)

    def _failure_reason(self) -> str:
        """The reason of the failure that ended the run (see :mod:`bt_manip.failure_cause`):
        what the user needs to read first."""
        if callable(getattr(self.tree, "walk", None)):
            from bt_manip.failure_cause import failure_cause

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
            for method in ("stop_base", "hold_arm"):
                fn = getattr(robot, method, None)
                if callable(fn):
                    fn()
