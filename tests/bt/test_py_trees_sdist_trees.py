"""The trees py_trees' own tests tick (from the sdist of the installed version) tick the same
through bt-manip, node by node, tick by tick.

The sdist is downloaded into the cache at test time (:mod:`tests.bt.py_trees_sdist`; the
tests are skipped, with the reason, when it cannot be had). Every root one of its tests ticks
is built again by the test's own code, as it stood before its first tick, and ticked as many
times as the test ticked it (at most :data:`MAX_TICKS`) three ways
(:mod:`tests.bt.py_trees_side_by_side`): by py_trees, by ``from_py_trees(root)`` and by
``from_py_trees(root, builtins=False)``, all reading one manual clock (the sdist's modules'
``time`` too). After every tick each node's status, the leaves' calls and the blackboard must
agree; with BT.CPP built-ins, py_trees' extra ``terminate(INVALID)`` on a child that had
already finished is left out (documented). What the test did to the tree between its ticks
(changing a child's queue, writing the blackboard...) is not replayed: both engines tick the
tree as it was built.
"""

from __future__ import annotations

import copy
import sys
import time
import types
from typing import Any

import py_trees
import pytest

from tests.bt import py_trees_sdist as sdist
from tests.bt.py_trees_side_by_side import (
    WAYS,
    Clocked,
    differences,
    fresh_blackboard,
    normalised,
    run_way,
)

MAX_TICKS = 60
"""Ticks at most (two tests tick a 2 s wait until it ends, 48 and 190 times in real time)."""
TREE_WAYS = WAYS[:3]  # py_trees, builtins, py_trees_nodes

FINISHED_CHILDREN = ("documented terminate(INVALID) difference: the Parallel's children had "
                     "finished in an earlier tree of the test, and py_trees' Parallel, starting, "
                     "calls terminate(INVALID) on them (not RUNNING)")
KNOWN: dict[str, str] = {
    **{f"test_parallels::test_parallel_failure#{i}": FINISHED_CHILDREN for i in (4, 5, 6)},
}
"""Trees whose side-by-side run differs, and why (besides :data:`PORT_MODULES`)."""


def known(tree_id: str) -> str | None:
    """Why the tree ``tree_id`` is known not to tick alike, or None."""
    return KNOWN.get(tree_id)


def collect() -> tuple[list[sdist.Recorded], str]:
    """The roots the sdist's tests tick, or none and why."""
    try:
        folder = sdist.sdist_tests(sdist.VERSION)
    except sdist.Unavailable as e:
        return [], str(e)
    saved = dict(py_trees.blackboard.Blackboard.__dict__)
    try:
        cases, broken = sdist.cases(folder)
        found: list[sdist.Recorded] = []
        for case in cases:
            found.extend(sdist.record(case)[0])
    finally:
        for attribute in ("storage", "metadata", "clients", "activity_stream"):
            setattr(py_trees.blackboard.Blackboard, attribute, saved[attribute])
    assert not broken, f"sdist test modules that did not import: {broken}"
    return found, ""


RECORDED, UNAVAILABLE = collect()
BY_ID = {r.id: r for r in RECORDED}


def sdist_modules() -> list[types.ModuleType]:
    prefix = sdist.PACKAGE + "."
    return [m for name, m in sys.modules.items() if name.startswith(prefix)]


def builder(recorded: sdist.Recorded) -> Any:
    """A factory building ``recorded``'s root again, the sdist's modules reading the manual
    clock of the run that calls it (``run_way`` installs it in ``py_trees.timers``), a test's
    ``time.sleep()`` moving it on."""
    def build() -> py_trees.behaviour.Behaviour:
        clock = py_trees.timers.time.time.__self__  # the ManualClock of Clocked's fake
        fake = types.SimpleNamespace(time=clock.now, monotonic=clock.now, sleep=clock.advance)
        for module in sdist_modules():
            if "time" in vars(module):
                module.time = fake  # type: ignore[attr-defined]
        return sdist.build(recorded)
    return build


@pytest.fixture
def real_time_restored() -> Any:
    yield
    for module in sdist_modules():
        if "time" in vars(module):
            module.time = time  # type: ignore[attr-defined]
    fresh_blackboard({})


def mismatches(recorded: sdist.Recorded) -> dict[str, list[str]]:
    """What differs from py_trees' own run, way by way."""
    factory = builder(recorded)
    fresh_blackboard({})
    with Clocked():
        factory()
    seed = dict(py_trees.blackboard.Blackboard.storage)  # what the test wrote before ticking
    ticks = min(recorded.ticks, MAX_TICKS)
    runs = {way: normalised(run_way(way, factory, ticks, copy.deepcopy(seed)))
            for way in TREE_WAYS}
    found = {}
    for way in TREE_WAYS[1:]:
        problems = list(differences(runs["py_trees"], runs[way],
                                    strict_calls=way == "py_trees_nodes"))
        if problems:
            found[way] = problems
    return found


def params() -> list[Any]:
    if not RECORDED:
        return [pytest.param("", marks=pytest.mark.skip(reason=UNAVAILABLE))]
    return [pytest.param(r.id, marks=pytest.mark.xfail(reason=reason, strict=True))
            if (reason := known(r.id)) else r.id for r in RECORDED]


@pytest.mark.usefixtures("real_time_restored")
@pytest.mark.parametrize("tree", params())
def test_sdist_tree_ticks_alike(tree: str) -> None:
    assert mismatches(BY_ID[tree]) == {}


def test_known_differences_are_trees_found() -> None:
    if not RECORDED:
        pytest.skip(UNAVAILABLE)
    assert set(KNOWN) <= set(BY_ID)
