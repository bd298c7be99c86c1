"""One episode: a world built for a seed, a tree loaded against it, run to the end.

``bt-manip run`` runs one episode with live views attached; ``bt-manip bench`` runs many in
worker processes. Both go through :class:`Episode`, so an episode in a bench is exactly the run
that ``bt-manip run`` with the same seed would give. The episode is the one place that wires a
run: the world, the run's context (:class:`~bt_manip.run.context.RunContext`), the faults, the
tree, the :class:`~bt_manip.run.runner.Runner` and what the report adds to the runner's (the
injected faults, the as-built table of a world written by ``bt-manip bim``).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import bt_manip.behaviours  # importing it registers the robot behaviours
import bt_manip.nav2  # noqa: F401  (and Nav2's nodes)
from bt_manip.bim.as_built import as_built, schedule_for, table_text
from bt_manip.bt import load_tree
from bt_manip.bt.blackboard import Blackboard
from bt_manip.bt.tree import Tree
from bt_manip.clock import MonotonicClock
from bt_manip.errors import InputError
from bt_manip.groot import BtlogWriter, TreeMonitor
from bt_manip.plugins import import_modules
from bt_manip.run.context import RunContext
from bt_manip.run.faults import FaultInjector, FaultSpec, inject_node_failures
from bt_manip.run.hooks import RunHook, TickCallback, close_hooks
from bt_manip.run.report import RunReport
from bt_manip.run.runner import Runner, RunOptions
from bt_manip.sim.world import World


@dataclass(frozen=True)
class EpisodeSpec:
    """Everything that defines a run (frozen: change a copy with
    :func:`dataclasses.replace`)."""

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

    The tree's context is the run's :class:`~bt_manip.run.context.RunContext` (``context``):
    the world's clock, the fault injector (``faults``, whose node failures are wrapped around
    their nodes here), the overlay, and each robot's navigator and IK, built on first use.

    Raises :class:`~bt_manip.errors.InputError` while building when the tree or world is bad.
    """

    def __init__(self, spec: EpisodeSpec) -> None:
        self.spec = spec
        self.world: World | None = None
        self._monitor: TreeMonitor | None = None
        _load_behaviours(spec.imports)
        if spec.world:
            self.world = World(spec.world, seed=spec.seed)
        try:
            clock = self.world.clock if self.world is not None else MonotonicClock()
            self.faults = FaultInjector(list(spec.inject), seed=spec.seed, clock=clock)
            self.context = RunContext(clock=clock, world=self.world, faults=self.faults)
            self.tree: Tree = load_tree(
                spec.tree,
                tree_id=spec.tree_id,
                models=spec.models,
                context=self.context,
                # entries given by the user (--bb) are typed as a script would type them
                blackboard=Blackboard.from_dict(dict(spec.blackboard), typed=False),
            )
            if self.world is None:
                refuse_world_nodes(self.tree, spec.tree)
            inject_node_failures(self.tree, self.faults)
        except BaseException:
            self.close()
            raise

    def monitor(self) -> TreeMonitor:
        """The tree's :class:`~bt_manip.groot.TreeMonitor` (made on first use), stamping status
        changes with the run's time: the sim clock with a world, the monotonic clock without."""
        if self._monitor is None:
            self._monitor = TreeMonitor(self.tree, self.context.clock.now)
        return self._monitor

    def run(self, hooks: Sequence[RunHook | TickCallback] = (),
            options: RunOptions | None = None) -> RunReport:
        """Tick to the end and return the report (faults injected are in ``extra``).

        ``options`` replace the spec's (``bt-manip run`` paces a run it shows live). The runner
        owns ``hooks`` (and the .btlog writer of ``spec.btlog``): they are closed when this
        returns or raises."""
        watching = list(hooks)
        if self.spec.btlog:
            try:
                writer = BtlogWriter(self.spec.btlog, self.monitor())
            except OSError as e:
                close_hooks(watching)
                raise InputError.single(
                    "--btlog", None, f"cannot write {self.spec.btlog}: {e.strerror}") from None
            except BaseException:
                close_hooks(watching)
                raise
            watching.insert(0, writer)  # closed first, as soon as the run ends
        opts = options if options is not None else self.spec.options
        report = Runner(self.tree, self.world, opts, on_tick=watching).run()
        report.tree = self.spec.tree
        report.world = self.spec.world or ""
        report.seed = self.spec.seed if self.world is not None else None
        if self.spec.inject:
            report.extra["inject"] = [f.text() for f in self.spec.inject]
            report.extra["injected"] = self.faults.report()
        rows = self._as_built()
        if rows is not None:
            report.as_built = rows
            report.notes.append(table_text(rows))
        return report

    def _as_built(self) -> list[dict[str, Any]] | None:
        """The as-built table when the world was written by ``bt-manip bim`` (see
        :mod:`bt_manip.bim.as_built`), else None."""
        if self.world is None or self.world.path is None:
            return None
        schedule = schedule_for(self.world.path)
        return as_built(self.world, schedule) if schedule is not None else None

    def close(self) -> None:
        if self._monitor is not None:
            self._monitor.close()
            self._monitor = None
        if self.world is not None:
            self.world.close()
            self.world = None

    def __enter__(self) -> Episode:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def refuse_world_nodes(tree: Tree, source: str) -> None:
    """InputError naming the first node of ``tree`` that acts on a world (``NEEDS_WORLD``),
    for a run given none: it would fail at its first tick."""
    for node in tree.nodes():
        if getattr(type(node), "NEEDS_WORLD", False):
            named = f" '{node.name}'" if node.name != node.NODE_ID else ""
            raise InputError.single(
                node.xml_file or source, node.xml_line,
                f"{node.NODE_ID}{named} acts on a simulated world, and no world is given; run "
                "with --world W.yaml (`bt-manip examples` lists the shipped worlds)")


def _load_behaviours(imports: Sequence[str] = ()) -> None:
    """Register the user's modules' nodes with the node registry (importing them does it;
    the robot behaviours and Nav2's nodes are registered by this module's imports);
    InputError naming ``--import`` when a user's module fails."""
    problems = import_modules(imports)
    if problems:
        raise InputError(problems)
