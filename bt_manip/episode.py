"""One episode: a world built for a seed, a tree loaded against it, run to the end.

``bt-manip run`` runs one episode with live views attached; ``bt-manip bench`` runs many in
worker processes. Both go through :class:`Episode`, so an episode in a bench is exactly the run
that ``bt-manip run`` with the same seed would give.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

from bt_manip.bt.blackboard import Blackboard
from bt_manip.faults import FaultInjector, FaultSpec, inject_node_failures
from bt_manip.run_context import RunContext
from bt_manip.runner import Runner, RunOptions, RunReport


@dataclass
class EpisodeSpec:
    """Everything that defines a run."""

    tree: str
    world: str | None = None
    seed: int = 0
    tree_id: str | None = None
    models: list[str] = field(default_factory=list)
    blackboard: dict[str, Any] = field(default_factory=dict)
    inject: list[FaultSpec] = field(default_factory=list)
    options: RunOptions = field(default_factory=RunOptions)
    imports: list[str] = field(default_factory=list)
    """User modules that register nodes (``--import``), imported before the tree loads."""
    btlog: str | None = None
    """Write the run's status changes to this .btlog file (Groot2 replays it)."""


class Episode:
    """Builds the world and the tree of one run; use as a context manager.

    The tree's context is the run's :class:`~bt_manip.run_context.RunContext` (``context``):
    the world's clock, the fault injector (``faults``, whose node failures are wrapped around
    their nodes here), the overlay, and each robot's navigator and IK, built on first use.

    Raises :class:`~bt_manip.errors.InputError` while building when the tree or world is bad.
    """

    def __init__(self, spec: EpisodeSpec) -> None:
        from bt_manip.bt import load_tree
        from bt_manip.clock import MonotonicClock

        self.spec = spec
        self.world: Any = None
        _load_behaviours(spec.imports)
        if spec.world:
            from bt_manip.sim.world import World

            self.world = World(spec.world, seed=spec.seed)
        try:
            clock = self.world.clock if self.world is not None else MonotonicClock()
            self.faults = FaultInjector(list(spec.inject), seed=spec.seed, clock=clock)
            self.context = RunContext(clock=clock, world=self.world, faults=self.faults)
            self.tree = load_tree(
                spec.tree,
                tree_id=spec.tree_id,
                models=spec.models,
                context=self.context,
                # entries given by the user (--bb) are typed as a script would type them
                blackboard=Blackboard.from_dict(dict(spec.blackboard), typed=False),
            )
            inject_node_failures(self.tree, self.faults)
        except BaseException:
            self.close()
            raise
        self._monitor: Any = None

    def monitor(self) -> Any:
        """The tree's :class:`~bt_manip.groot.TreeMonitor` (made on first use), stamping status
        changes with the run's time: the sim clock with a world, the monotonic clock without."""
        if self._monitor is None:
            from bt_manip.groot import TreeMonitor

            self._monitor = TreeMonitor(self.tree, self.context.clock.now)
        return self._monitor

    def run(self, hooks: Sequence[Callable[[Runner], None]] = ()) -> RunReport:
        """Tick to the end and return the report (faults injected are in ``extra``)."""
        runner = Runner(self.tree, self.world, self.spec.options, on_tick=hooks)
        writer = None
        if self.spec.btlog:
            from bt_manip.errors import InputError
            from bt_manip.groot import BtlogWriter

            try:
                writer = BtlogWriter(self.spec.btlog, self.monitor())
            except OSError as e:
                raise InputError.single(
                    "--btlog", None, f"cannot write {self.spec.btlog}: {e.strerror}") from None
        try:
            report = runner.run()
        finally:
            if writer is not None:
                writer.close()
        report.tree = self.spec.tree
        report.world = self.spec.world or ""
        report.seed = self.spec.seed if self.world is not None else None
        if self.spec.inject:
            report.extra["inject"] = [f.text() for f in self.spec.inject]
            report.extra["injected"] = self.faults.report()
        return report

    def close(self) -> None:
        if getattr(self, "_monitor", None) is not None:
            self._monitor.close()
            self._monitor = None
        if self.world is not None:
            self.world.close()
            self.world = None

    def __enter__(self) -> Episode:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def _load_behaviours(imports: Sequence[str] = ()) -> None:
    """Register the robot behaviours and the user's modules' nodes with the node registry
    (importing them does it); InputError naming ``--import`` when a user's module fails."""
    import bt_manip.behaviours
    import bt_manip.nav2  # noqa: F401
    from bt_manip.errors import InputError
    from bt_manip.plugins import import_modules

    problems = import_modules(imports)
    if problems:
        raise InputError(problems)
