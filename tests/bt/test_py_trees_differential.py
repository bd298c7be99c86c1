"""Differential test: random py_trees trees, ticked by py_trees and converted by from_py_trees.

Each seed builds the same random tree twice (every composite and decorator of py_trees, its own
leaves, blackboard reads and writes, clock-based nodes, subclasses of py_trees' nodes): py_trees
ticks one, the other is converted with ``from_py_trees`` and ticked by bt-manip. After every
tick the root statuses must be equal, and so must the log of what the leaves did (each
``initialise()``, each ``update()`` with its result, each ``terminate()``); at the end the
blackboards hold the same values. Both engines read one manual clock, advanced by the same step
after every tick.

Half of the seeds convert with BT.CPP built-ins where they tick alike (``builtins=True``);
there py_trees' extra ``terminate(INVALID)`` on a child that had already finished (see
:mod:`bt_manip.bt.pytrees.convert`) is left out of the comparison; halting a RUNNING child is
compared. The other half convert every
node to its py_trees counterpart and compare every call.
"""

from __future__ import annotations

import itertools
import operator
import random
import types
from collections.abc import Callable
from typing import Any

import py_trees
import pytest
from py_trees.common import Status

from bt_manip.bt import from_py_trees
from bt_manip.bt.context import TreeContext
from bt_manip.clock import ManualClock
from tests.bt.py_trees_side_by_side import spy

TREES = 1000
TICKS = 12
STEP = 0.25  # seconds of clock per tick
KEYS = ("a", "/b", "c")
Log = list[tuple[str, str, str]]


class Builder:
    """Builds one random py_trees tree from a seed; leaves log their calls into ``log``."""

    def __init__(self, seed: int) -> None:
        self.rng = random.Random(seed)
        self.log: Log = []
        self.count = 0

    def name(self, prefix: str) -> str:
        self.count += 1
        return f"{prefix}{self.count}"

    def tree(self, depth: int = 0) -> py_trees.behaviour.Behaviour:
        roll = self.rng.random()
        if depth >= 4 or (depth > 0 and roll < 0.1 + 0.15 * depth):
            return self.leaf()
        if roll < 0.65:
            return self.composite(depth)
        return self.decorator(depth)

    def composite(self, depth: int) -> py_trees.behaviour.Behaviour:
        rng = self.rng
        n = rng.choice([0, 1, 2, 2, 3, 3])
        kind = rng.choice(["seq", "sel", "par"])
        if kind == "par":
            n = max(n, 1)
        children = [self.tree(depth + 1) for _ in range(n)]
        memory = rng.random() < 0.5
        if kind == "seq":
            return py_trees.composites.Sequence(self.name("Seq"), memory, children)
        if kind == "sel":
            selector = OwnSelector if rng.random() < 0.2 else py_trees.composites.Selector
            return selector(self.name("Sel"), memory, children)
        policies = py_trees.common.ParallelPolicy
        which = rng.choice(["all", "one", "selected"])
        if which == "all":
            policy: Any = policies.SuccessOnAll(synchronise=rng.random() < 0.5)
        elif which == "one":
            policy = policies.SuccessOnOne()
        else:
            picked = rng.sample(children, rng.randint(1, len(children)))
            policy = policies.SuccessOnSelected(picked, synchronise=rng.random() < 0.5)
        return py_trees.composites.Parallel(self.name("Par"), policy, children)

    def decorator(self, depth: int) -> py_trees.behaviour.Behaviour:
        rng = self.rng
        d = py_trees.decorators
        child = self.tree(depth + 1)
        kind = rng.randrange(17)
        name = self.name("Dec")
        simple = [d.Inverter, d.RunningIsFailure, d.RunningIsSuccess, d.FailureIsSuccess,
                  d.FailureIsRunning, d.SuccessIsFailure, d.SuccessIsRunning, d.PassThrough,
                  d.Count]
        if kind < len(simple):
            return simple[kind](name=name, child=child)
        if kind == 9:
            repeat = OwnRepeat if rng.random() < 0.3 else d.Repeat
            return repeat(name, child, rng.choice([1, 2, 3, -1]))
        if kind == 10:
            return d.Retry(name, child, rng.choice([1, 2, 3]))
        if kind == 11:
            return d.Timeout(name, child, rng.choice([0.3, 1.0]))
        if kind == 12:
            return d.OneShot(name, child, rng.choice(list(py_trees.common.OneShotPolicy)))
        if kind == 13:
            return d.Condition(name, child, rng.choice([Status.SUCCESS, Status.FAILURE,
                                                        Status.RUNNING]))
        if kind == 14:
            return d.StatusToBlackboard(name, child, "st")
        if kind == 15:
            return d.ForEach(name, child, "items", "c")
        if rng.random() < 0.5:
            return d.EternalGuard(name, child, has_a, blackboard_keys=["a"])
        return d.EternalGuard(name, child, every_third(rng.randint(0, 2)))

    def leaf(self) -> py_trees.behaviour.Behaviour:
        rng = self.rng
        b = py_trees.behaviours
        name = self.name("L")
        key = rng.choice(KEYS)
        status = rng.choice([Status.SUCCESS, Status.FAILURE, Status.RUNNING])
        makers: list[Callable[[], py_trees.behaviour.Behaviour]] = [
            lambda: b.Success(name),
            lambda: b.Failure(name),
            lambda: b.Running(name),
            lambda: b.Dummy(name),
            lambda: b.Periodic(name, rng.randint(1, 3)),
            lambda: b.StatusQueue(name, [rng.choice(list(Status)[:3]) for _ in range(3)],
                                  rng.choice([None, status])),
            lambda: b.SuccessEveryN(name, rng.randint(1, 3)),
            lambda: b.TickCounter(name, rng.randint(0, 3), status),
            lambda: py_trees.timers.Timer(name, rng.choice([0.0, 0.5, 1.0])),
            lambda: b.BlackboardToStatus(name, "st"),
            lambda: b.CheckBlackboardVariableExists(name, key),
            lambda: b.WaitForBlackboardVariable(name, key),
            lambda: b.UnsetBlackboardVariable(name, key),
            lambda: b.SetBlackboardVariable(name, key, rng.randint(0, 3), rng.random() < 0.5),
            lambda: b.CheckBlackboardVariableValue(name, py_trees.common.ComparisonExpression(
                key, rng.randint(0, 3), operator.ge)),
            lambda: b.ProbabilisticBehaviour(name, [1.0, 1.0, 1.0]),
        ]
        node = rng.choice(makers)()
        self.spy(node)
        return node

    def spy(self, node: py_trees.behaviour.Behaviour) -> None:
        if not isinstance(node, py_trees.timers.Timer):  # Timer becomes PyTreesTimer
            spy(node, self.log)


class OwnRepeat(py_trees.decorators.Repeat):
    """A user's subclass of a py_trees decorator (converted as the user's own class)."""


class OwnSelector(py_trees.composites.Selector):
    """A user's subclass of a py_trees composite, with an initialise of its own."""

    def initialise(self) -> None:
        self.feedback_message = "started"


def has_a(blackboard: Any) -> bool:
    return bool(blackboard.exists("a"))


def every_third(offset: int) -> Callable[[], bool]:
    counter = itertools.count(offset)
    return lambda: next(counter) % 3 != 0


def seeded_storage() -> dict[str, Any]:
    return {"/a": 1, "/items": [1, 2, 3], "/st": Status.SUCCESS}


@pytest.fixture
def clock(monkeypatch: pytest.MonkeyPatch) -> ManualClock:
    """One manual clock for py_trees' Timer and Timeout and for the converted trees."""
    manual = ManualClock()
    fake = types.SimpleNamespace(time=manual.now, monotonic=manual.now)
    monkeypatch.setattr(py_trees.timers, "time", fake)
    monkeypatch.setattr(py_trees.decorators, "time", fake)
    storage = py_trees.blackboard.Blackboard
    monkeypatch.setattr(storage, "storage", {})
    monkeypatch.setattr(storage, "metadata", {})
    monkeypatch.setattr(storage, "clients", {})
    return manual


def run_ticks(builder: Builder, seed: int, clock: ManualClock, tick: Callable[[], str]
              ) -> tuple[list[str], Log]:
    """Tick ``TICKS`` times from time 0 with ``random`` seeded: each tick's status ("raised"
    when it raised: both engines must raise at the same tick, the converted one with a
    TreeRuntimeError naming the node) and the log, a ``tick`` entry before each tick's."""
    clock.t = 0.0
    random.seed(seed)
    statuses = []
    logs: Log = []
    for _ in range(TICKS):
        builder.log.clear()
        try:
            statuses.append(tick())
        except Exception:
            statuses.append("raised")
        logs.append(("tick", "", ""))
        logs.extend(builder.log)
        clock.advance(STEP)
    return statuses, logs


def run_py_trees(seed: int, clock: ManualClock) -> tuple[list[str], Log, dict[str, Any]]:
    builder = Builder(seed)
    root = builder.tree()
    storage = seeded_storage()
    py_trees.blackboard.Blackboard.storage = storage

    def tick() -> str:
        root.tick_once()
        return str(root.status.name)

    statuses, logs = run_ticks(builder, seed, clock, tick)
    return statuses, logs, {k: storage.get(k) for k in ("/a", "/b", "/c", "/st")}


def run_converted(seed: int, clock: ManualClock, builtins: bool
                  ) -> tuple[list[str], Log, dict[str, Any]]:
    builder = Builder(seed)
    root = builder.tree()
    tree = from_py_trees(root, builtins=builtins, context=TreeContext(clock=clock),
                         blackboard={k.lstrip("/"): v for k, v in seeded_storage().items()})
    statuses, logs = run_ticks(builder, seed, clock, lambda: str(tree.tick().value))
    bb = tree.blackboard
    return statuses, logs, {"/" + k: bb.get_or(k) for k in ("a", "b", "c", "st")}


def comparable(log: Log, builtins: bool) -> Log:
    if not builtins:
        return log
    return [entry for entry in log if entry[2] != "INVALID (was not RUNNING)"]


def test_random_py_trees_trees_tick_alike_after_conversion(clock: ManualClock) -> None:
    mismatches = []
    for seed in range(TREES):
        builtins = seed % 2 == 0
        expected = run_py_trees(seed, clock)
        got = run_converted(seed, clock, builtins)
        if (expected[0] != got[0] or comparable(expected[1], builtins)
                != comparable(got[1], builtins) or expected[2] != got[2]):
            mismatches.append((seed, builtins, expected, got))
    assert not mismatches, _describe(mismatches[0])


def _describe(mismatch: tuple[Any, ...]) -> str:
    seed, builtins, expected, got = mismatch
    root = Builder(seed).tree()
    lines = [f"seed {seed} (builtins={builtins}):",
             py_trees.display.ascii_tree(root),
             f"py_trees statuses:  {expected[0]}", f"converted statuses: {got[0]}",
             f"py_trees blackboard:  {expected[2]}", f"converted blackboard: {got[2]}"]
    a, b = comparable(expected[1], builtins), comparable(got[1], builtins)
    for i, (x, y) in enumerate(itertools.zip_longest(a, b)):
        if x != y:
            lines.append(f"first log difference at entry {i}: py_trees {x}, converted {y}")
            lines.append(f"py_trees log around it:  {a[max(0, i - 6):i + 3]}")
            lines.append(f"converted log around it: {b[max(0, i - 6):i + 3]}")
            break
    return "\n".join(lines)


def test_the_generator_covers_every_composite_decorator_and_leaf(clock: ManualClock) -> None:
    seen: set[str] = set()
    for seed in range(TREES):
        root = Builder(seed).tree()
        for node in root.iterate():
            seen.add(type(node).__name__)
            if isinstance(node, py_trees.composites.Composite) and hasattr(node, "memory"):
                seen.add(f"{type(node).__name__}(memory={node.memory})")
            if isinstance(node, py_trees.composites.Parallel):
                seen.add(type(node.policy).__name__)
    decorators = {name for name, cls in vars(py_trees.decorators).items()
                  if isinstance(cls, type) and issubclass(cls, py_trees.decorators.Decorator)
                  and cls is not py_trees.decorators.Decorator}
    composites = {"Sequence(memory=True)", "Sequence(memory=False)", "Selector(memory=True)",
                  "Selector(memory=False)", "SuccessOnAll", "SuccessOnOne", "SuccessOnSelected"}
    leaves = {"Success", "Failure", "Running", "Dummy", "Periodic", "StatusQueue",
              "SuccessEveryN", "TickCounter", "Timer", "BlackboardToStatus",
              "CheckBlackboardVariableExists", "WaitForBlackboardVariable",
              "UnsetBlackboardVariable", "SetBlackboardVariable", "CheckBlackboardVariableValue",
              "ProbabilisticBehaviour"}
    assert decorators - seen == set()
    assert composites - seen == set()
    assert leaves - seen == set()
    assert {"OwnRepeat", "OwnSelector"} <= seen
