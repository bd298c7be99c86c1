"""Ticking one py_trees tree four ways and recording what happens, tick by tick.

A *run* builds a fresh tree with a factory, ticks it, and records after every tick each node's
status (as py_trees' view shows it: the ``status`` attribute, in ``iterate()`` order), the
leaves' calls (``initialise``, ``update`` with its result, ``terminate`` with its status) and
the blackboard. The ways:

- ``py_trees``: py_trees ticks the tree itself (``root.tick_once()``);
- ``builtins``: ``from_py_trees(root)`` (BT.CPP built-ins where they tick alike);
- ``py_trees_nodes``: ``from_py_trees(root, builtins=False)``;
- ``xml``: ``to_xml`` of the ``builtins`` conversion, loaded back with ``load_tree``.

All four read one manual clock (py_trees' timers and ``Timeout`` too) and start from the
same seeded blackboard and ``random`` seed.
"""

from __future__ import annotations

import dataclasses
import enum
import random
import re
import types
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from typing import Any

import py_trees
from py_trees.common import Status

from bt_manip.bt import from_py_trees, load_tree_string, to_xml
from bt_manip.bt.context import TreeContext
from bt_manip.bt.node import TreeRuntimeError
from bt_manip.bt.pytrees.leaf import PyTreesLeaf
from bt_manip.bt.subtree import SubTree
from bt_manip.clock import ManualClock

WAYS = ("py_trees", "builtins", "py_trees_nodes", "xml")
STEP = 0.25  # seconds of clock per tick
Call = tuple[str, str, str]


@dataclass
class Run:
    """What one way of ticking a tree did."""

    statuses: list[list[tuple[str, str]]] = field(default_factory=list)
    bt_statuses: list[list[tuple[str, str]]] = field(default_factory=list)
    calls: list[list[Call]] = field(default_factory=list)
    blackboards: list[dict[str, Any]] = field(default_factory=list)
    error: str = ""


def plain(value: Any) -> Any:
    """A comparable form of a blackboard value (objects without ``__eq__`` by their fields)."""
    if isinstance(value, (str, int, float, bool, type(None), enum.Enum)):
        return value
    if isinstance(value, dict):
        return {str(k): plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [plain(v) for v in value]
    if hasattr(value, "__dict__") and type(value).__eq__ is object.__eq__:
        return (type(value).__name__, plain(vars(value)))
    return value


def spy(behaviour: py_trees.behaviour.Behaviour, log: list[Call]) -> None:
    """Log the behaviour's ``initialise``/``update``/``terminate`` calls into ``log``."""
    name = behaviour.name
    initialise, update, terminate = behaviour.initialise, behaviour.update, behaviour.terminate

    def logged_initialise() -> None:
        log.append(("initialise", name, ""))
        initialise()

    def logged_update() -> Status:
        result = update()
        log.append(("update", name, result.name))
        return result

    def logged_terminate(new_status: Status) -> None:
        was = "" if behaviour.status == Status.RUNNING else " (was not RUNNING)"
        log.append(("terminate", name, new_status.name + was))
        terminate(new_status)

    behaviour.initialise = logged_initialise  # type: ignore[method-assign]
    behaviour.update = logged_update  # type: ignore[method-assign]
    behaviour.terminate = logged_terminate  # type: ignore[method-assign]


def is_leaf(node: py_trees.behaviour.Behaviour) -> bool:
    return not isinstance(node, (py_trees.composites.Composite, py_trees.decorators.Decorator)) \
        and not node.children


def spy_leaves(root: py_trees.behaviour.Behaviour, log: list[Call]) -> None:
    for node in root.iterate():
        if isinstance(node, PyTreesLeaf):
            spy(node.behaviour, log)
        elif is_leaf(node) and not isinstance(node, py_trees.timers.Timer):
            spy(node, log)


def statuses(root: py_trees.behaviour.Behaviour) -> list[tuple[str, str]]:
    """Each node's (name, py_trees status), SubTree nodes of a loaded tree left out."""
    return [(node.name, node.status.name) for node in root.iterate()
            if not isinstance(node, SubTree)]


def bt_statuses(root: py_trees.behaviour.Behaviour) -> list[tuple[str, str]]:
    """Each node's (name, BT.CPP status) in a bt-manip tree, SubTree nodes left out."""
    return [(node.name, getattr(node, "bt_status", node.status).name)
            for node in root.iterate() if not isinstance(node, SubTree)]


def storage_snapshot(storage: Any) -> dict[str, Any]:
    return {key.lstrip("/"): plain(value) for key, value in storage.items()}


class Clocked:
    """A manual clock that py_trees' timers and ``Timeout`` read while it is installed."""

    def __init__(self) -> None:
        self.clock = ManualClock()
        self._saved: list[tuple[Any, str, Any]] = []

    def __enter__(self) -> Clocked:
        fake = types.SimpleNamespace(time=self.clock.now, monotonic=self.clock.now,
                                     sleep=lambda _s: None)
        for module in (py_trees.timers, py_trees.decorators):
            self._saved.append((module, "time", module.time))
            module.time = fake  # type: ignore[attr-defined]
        return self

    def __exit__(self, *exc: object) -> None:
        for module, attribute, value in reversed(self._saved):
            setattr(module, attribute, value)
        self._saved.clear()


def fresh_blackboard(seed: dict[str, Any]) -> None:
    """Empty py_trees' global blackboard, then write ``seed`` (absolute keys)."""
    storage = py_trees.blackboard.Blackboard
    storage.storage = {}
    storage.metadata = {}
    storage.clients = {}
    storage.storage.update(seed)


Factory = Callable[[], py_trees.behaviour.Behaviour]
Converter = Callable[[py_trees.behaviour.Behaviour, ManualClock, dict[str, Any]], Any]


def _ticks(tick: Callable[[], Any], root: Any, log: list[Call], bb: Callable[[], dict[str, Any]],
           ticks: int, clock: ManualClock, seed: int) -> Run:
    run = Run()
    clock.t = 0.0
    random.seed(seed)
    for _ in range(ticks):
        log.clear()
        try:
            tick()
        except Exception as e:  # both engines must raise the same error at the same tick
            run.error = raised(e)
            break
        finally:
            run.calls.append(list(log))
        run.statuses.append(statuses(root))
        run.bt_statuses.append(bt_statuses(root))
        run.blackboards.append(bb())
        clock.advance(STEP)
    return run


def raised(error: Exception) -> str:
    """What was raised: py_trees' own exception, also where bt-manip reports it as a
    :class:`~bt_manip.bt.node.TreeRuntimeError` naming the node (raised from it)."""
    if isinstance(error, TreeRuntimeError) and isinstance(error.__cause__, Exception):
        error = error.__cause__
    return f"{type(error).__name__}: {error}"


def run_way(way: str, factory: Factory, ticks: int, seed_bb: dict[str, Any],
            setup: bool = False, seed: int = 0) -> Run:
    """Build the tree with ``factory`` and tick it ``ticks`` times the way ``way``."""
    fresh_blackboard(seed_bb)
    with Clocked() as clocked:
        clock = clocked.clock
        root = factory()
        log: list[Call] = []
        if way == "py_trees":
            spy_leaves(root, log)
            if setup:
                root.setup_with_descendants()
            storage = py_trees.blackboard.Blackboard.storage
            return _ticks(root.tick_once, root, log, lambda: storage_snapshot(storage),
                          ticks, clock, seed)
        entries = {k.lstrip("/"): v for k, v in seed_bb.items()}
        tree = from_py_trees(root, builtins=way != "py_trees_nodes",
                             context=TreeContext(clock=clock), blackboard=entries)
        if way == "xml":
            # XML holds the tree, not its blackboard: the loaded tree starts with the
            # entries the converted one started with (the seed, and what py_trees'
            # setup_ports() had written: its ports' constants and outputs' defaults)
            start = {k: tree.blackboard.get(k) for k in tree.blackboard.keys()}  # noqa: SIM118
            text = to_xml(tree)
            fresh_blackboard(seed_bb)
            tree = load_tree_string(text, context=TreeContext(clock=clock), blackboard=start)
        spy_leaves(tree.root, log)
        if setup:
            tree.root.setup_with_descendants()
        blackboard = tree.blackboard
        return _ticks(tree.tick, tree.root, log,
                      lambda: {k: plain(blackboard.get(k)) for k in blackboard.keys()},  # noqa: SIM118
                      ticks, clock, seed)


UUID = re.compile(r"_[0-9a-f]{8}-[0-9a-f]{4}-[0-9a-f]{4}-[0-9a-f]{4}-[0-9a-f]{12}")


def same_each_build(value: Any) -> Any:
    """``value`` without what differs from one build of a tree to the next: the uuids that
    py_trees' XML parser appends to names and that name the blackboard keys of ports left
    unremapped or given a constant, iterators (the blackboard compares them as objects)."""
    if isinstance(value, str):
        return UUID.sub("_<uuid>", value)
    if isinstance(value, dict):
        return {same_each_build(k): same_each_build(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return type(value)(same_each_build(v) for v in value)
    if isinstance(value, Iterator):
        return f"<{type(value).__name__}>"
    return value


def normalised(run: Run) -> Run:
    """``run`` as :func:`same_each_build` sees it."""
    return Run(*(same_each_build(getattr(run, f.name)) for f in dataclasses.fields(Run)))


def comparable(calls: list[Call]) -> list[Call]:
    """Calls without py_trees' extra ``terminate(INVALID)`` of a child that had finished
    (documented: a BT.CPP parent resets such a child without calling it)."""
    return [c for c in calls if c[2] != "INVALID (was not RUNNING)"]


def differences(expected: Run, got: Run, strict_calls: bool, bt_view: bool = False
                ) -> Iterator[str]:
    """Where ``got`` differs from ``expected``, tick by tick (the first few): each node's
    status in py_trees' view (``bt_view``: BT.CPP's), the leaves' calls, the blackboard."""
    if expected.error != got.error:
        yield f"raised {expected.error or 'nothing'} / {got.error or 'nothing'}"
    views = (expected.bt_statuses, got.bt_statuses) if bt_view else \
        (expected.statuses, got.statuses)
    for tick, (a, b) in enumerate(zip(*views, strict=False), start=1):
        if a != b:
            diff = [(x, y) for x, y in zip(a, b, strict=False) if x != y] or [(a, b)]
            yield f"tick {tick}: statuses {diff[:3]}"
            return
    for tick, (a, b) in enumerate(zip(expected.calls, got.calls, strict=False), start=1):
        if not strict_calls:
            a, b = comparable(a), comparable(b)
        if a != b:
            yield f"tick {tick}: calls {a} / {b}"
            return
    pairs = zip(expected.blackboards, got.blackboards, strict=False)
    for tick, (a, b) in enumerate(pairs, start=1):
        if a != b:
            yield f"tick {tick}: blackboard {a} / {b}"
            return
    if len(expected.statuses) != len(got.statuses):
        yield f"ticks {len(expected.statuses)} / {len(got.statuses)}"
