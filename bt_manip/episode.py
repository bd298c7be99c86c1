"""One episode: a world built for a seed, a tree loaded against it, run to the end.

``bt-manip run`` runs one episode with live views attached; ``bt-manip bench`` runs many in
worker processes. Both go through :class:`Episode`, so an episode in a bench is exactly the run
that ``bt-manip run`` with the same seed would give. The episode is the one place that wires a
run: the world, the run's context (:class:`~bt_manip.run.context.RunContext`), the faults, the
tree, the :class:`~bt_manip.run.runner.Runner` and what the report adds to the runner's (the
injected faults, the as-built table of a world written by ``bt-manip bim``).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, fields
from pathlib import Path
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
from bt_manip.localization.runtime import localization_for_run
from bt_manip.plugins import import_modules
from bt_manip.run.context import RunContext
from bt_manip.run.faults import FaultInjector, FaultSpec, inject_node_failures, parse_fault
from bt_manip.run.hooks import RunHook, TickCallback, close_hooks
from bt_manip.run.report import RunReport
from bt_manip.run.runner import Runner, RunOptions
from bt_manip.sim.assets import shipped_or_given
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
    localize: bool = False
    """Localise the robots that have a laser and drive on the estimate (``--localize``; a
    world's ``localization:`` section turns it on too)."""


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
            self.localization = localization_for_run(self.world, spec.seed, spec.localize,
                                                     self.faults)
            self.context = RunContext(clock=clock, world=self.world, faults=self.faults,
                                      localization=self.localization)
            if self.localization is not None:  # the viewer and the replay draw what it sees
                for loc in self.localization.localizers.values():
                    loc.overlay = self.context.overlay
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
        sensing = [self.localization] if self.localization is not None else []
        report = Runner(self.tree, self.world, opts, on_tick=watching,
                        before_tick=sensing).run()
        report.tree = self.spec.tree
        report.world = self.spec.world or ""
        report.seed = self.spec.seed if self.world is not None else None
        if self.spec.inject:
            report.extra["inject"] = [f.text() for f in self.spec.inject]
            report.extra["injected"] = self.faults.report()
        if self.localization is not None:
            report.localization = self.localization.report()
            report.costmap = self.localization.costmap_report()
        planning = self.context.arm_planning()
        if planning:  # wall time: in the report, never on the blackboard
            report.extra["arm_planning"] = planning
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


def load_tree_with_nodes(path: str | Path, **kwargs: Any) -> Tree:
    """Load a tree file with every shipped node registered: ``bt_manip.load_tree``.

    The robot behaviours (:mod:`bt_manip.behaviours`) and Nav2's nodes (:mod:`bt_manip.nav2`)
    are registered by this module's imports. ``path`` is found as ``bt-manip run`` finds it: a
    relative path that names no file here but a shipped tree (``trees/sawyer_stack_two.xml``)
    is that tree. ``kwargs`` are those of :func:`bt_manip.bt.load_tree` (``tree_id``,
    ``models``, ``context``, ``blackboard``). A tree whose nodes act on a world ticks against
    one when given ``context=RunContext.for_world(world)``; :func:`run_tree` does all that.
    """
    return load_tree(shipped_or_given(str(path)), **kwargs)


def run_tree(
    tree: str | Path,
    world: str | Path | None = None,
    seed: int = 0,
    *,
    tree_id: str | None = None,
    blackboard: Mapping[str, Any] | None = None,
    inject: Sequence[str | FaultSpec] = (),
    imports: Sequence[str] = (),
    models: Sequence[str] = (),
    hooks: Sequence[RunHook | TickCallback] = (),
    **options: Any,
) -> RunReport:
    """Run a tree file on a world to its end, as ``bt-manip run`` does; the run report.

    Args:
        tree: the tree file (a shipped one by its relative path, ``trees/...``).
        world: the world file (``worlds/sawyer_table.yaml``), or None for a tree of built-in
            nodes only (run on the wall clock).
        seed: picks the world's random starts and the injected faults.
        tree_id: the tree to run (default: the file's main tree).
        blackboard: root blackboard entries set before the first tick (``--bb``).
        inject: faults, as ``--inject`` takes them (``"Attach:failure:0.3"``).
        imports: modules of your own that register nodes (``--import``).
        models: TreeNodesModel files.
        hooks: called after each tick with the runner (and closed at the end): look at the
            world (``runner.world``) or the tree while it runs.
        options: fields of :class:`~bt_manip.run.runner.RunOptions`: ``tick_hz``,
            ``max_sim_time``, ``max_ticks``, ``realtime``.

    Returns the :class:`~bt_manip.run.report.RunReport`: ``status`` (a
    :class:`~bt_manip.run.status.RunStatus`), ``reason``, ``cause``, sim and wall time, every
    node's final status; ``report.exit_code`` is what ``bt-manip run`` would exit with.

    Raises :class:`~bt_manip.errors.InputError` (every problem, as ``file:line: message``) for
    a bad tree or world, and TypeError for an unknown option.
    """
    known = {f.name for f in fields(RunOptions)}
    unknown = sorted(set(options) - known)
    if unknown:
        raise TypeError(f"run_tree() got unknown option(s) {', '.join(unknown)}; options are "
                        + ", ".join(sorted(known)))
    faults = [parse_fault(f) if isinstance(f, str) else f for f in inject]
    spec = EpisodeSpec(
        tree=shipped_or_given(str(tree)),
        world=shipped_or_given(str(world)) if world is not None else None,
        seed=int(seed),
        tree_id=tree_id,
        models=list(models),
        blackboard=dict(blackboard or {}),
        inject=faults,
        options=RunOptions(**options),
        imports=list(imports),
    )
    with Episode(spec) as episode:
        return episode.run(hooks)
