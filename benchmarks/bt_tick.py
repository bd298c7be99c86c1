"""Per-tick cost of a 1,000-node tree of BT.CPP built-ins, next to plain py_trees.

Both trees have the same shape: a Sequence root with 9 Sequences, each with 10 Sequences of
10 always-succeeding leaves (1 + 9 + 90 + 900 = 1,000 nodes), so every node is ticked at every
tick. A second shape mixes Fallbacks, Inverters and failing leaves. Prints JSON lines.

    .venv/bin/python benchmarks/bt_tick.py [--ticks N]
"""

from __future__ import annotations

import argparse
import json
import platform
import time
from collections.abc import Callable

import py_trees

from bt_manip.bt import Tree, TreeContext
from bt_manip.bt.controls import Fallback, Sequence
from bt_manip.bt.decorators import Inverter
from bt_manip.bt.leaves import AlwaysFailure, AlwaysSuccess
from bt_manip.cli.args import positive
from bt_manip.clock import ManualClock

FANOUT = (9, 10, 10)


def ours_all_success() -> Tree:
    def level(depth: int) -> list:  # type: ignore[type-arg]
        if depth == len(FANOUT):
            return []
        if depth == len(FANOUT) - 1:
            return [AlwaysSuccess() for _ in range(FANOUT[depth])]
        return [Sequence(children=level(depth + 1)) for _ in range(FANOUT[depth])]

    return Tree(Sequence(children=level(0)), context=TreeContext(clock=ManualClock()))


def theirs_all_success() -> py_trees.behaviour.Behaviour:
    def level(depth: int) -> list:  # type: ignore[type-arg]
        if depth == len(FANOUT) - 1:
            return [py_trees.behaviours.Success(name="s") for _ in range(FANOUT[depth])]
        return [py_trees.composites.Sequence(name="q", memory=False, children=level(depth + 1))
                for _ in range(FANOUT[depth])]

    return py_trees.composites.Sequence(name="root", memory=False, children=level(0))


def ours_mixed() -> Tree:
    # 9 Fallbacks of 10 Sequences (5 behind an Inverter) of 4 Inverter(AlwaysFailure) and
    # 2 AlwaysSuccess: 1,045 nodes, of which a Fallback ticks only up to its first success.
    def seq() -> Sequence:
        return Sequence(children=[Inverter(child=AlwaysFailure()) for _ in range(4)]
                        + [AlwaysSuccess(), AlwaysSuccess()])

    fallbacks = [Fallback(children=[Inverter(child=seq()) for _ in range(5)]
                          + [seq() for _ in range(5)]) for _ in range(9)]
    return Tree(Sequence(children=fallbacks), context=TreeContext(clock=ManualClock()))


def theirs_mixed() -> py_trees.behaviour.Behaviour:
    def seq() -> py_trees.composites.Sequence:
        kids: list[py_trees.behaviour.Behaviour] = [
            py_trees.decorators.Inverter(name="i", child=py_trees.behaviours.Failure(name="f"))
            for _ in range(4)]
        kids += [py_trees.behaviours.Success(name="s"), py_trees.behaviours.Success(name="s")]
        return py_trees.composites.Sequence(name="q", memory=False, children=kids)

    fallbacks = [py_trees.composites.Selector(
        name="f", memory=False,
        children=[py_trees.decorators.Inverter(name="i", child=seq()) for _ in range(5)]
        + [seq() for _ in range(5)]) for _ in range(9)]
    return py_trees.composites.Sequence(name="root", memory=False, children=fallbacks)


def count_ours(tree: Tree) -> int:
    return len(tree.nodes())


def count_theirs(root: py_trees.behaviour.Behaviour) -> int:
    return sum(1 for _ in root.iterate())


def timed(tick: Callable[[], object], ticks: int) -> float:
    for _ in range(max(ticks // 10, 5)):
        tick()
    best = float("inf")
    for _ in range(3):
        t0 = time.perf_counter()
        for _ in range(ticks):
            tick()
        best = min(best, (time.perf_counter() - t0) / ticks)
    return best


def tick_py_trees(root: py_trees.behaviour.Behaviour) -> Callable[[], object]:
    def tick() -> object:
        for _ in root.tick():
            pass
        return root.status

    return tick


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--ticks", type=positive(int), default=200)
    args = parser.parse_args()
    for shape, ours, theirs in (("all_success_sequences", ours_all_success, theirs_all_success),
                                ("mixed_fallback_inverter", ours_mixed, theirs_mixed)):
        tree = ours()
        root = theirs()
        n_ours, n_theirs = count_ours(tree), count_theirs(root)
        t_ours = timed(tree.tick, args.ticks)
        t_theirs = timed(tick_py_trees(root), args.ticks)
        assert tree.bt_status.value == root.status.name, (tree.bt_status, root.status)
        common = {"bench": "bt_tick", "shape": shape, "ticks": args.ticks,
                  "python": platform.python_version(), "py_trees": py_trees.version.__version__}
        rows = (("bt_manip", n_ours, t_ours), ("py_trees", n_theirs, t_theirs))
        for impl, nodes, per_tick in rows:
            print(json.dumps({**common, "impl": impl, "nodes": nodes,
                              "per_tick_us": round(per_tick * 1e6, 1),
                              "per_node_us": round(per_tick * 1e6 / nodes, 3),
                              "root_status": tree.bt_status.value}))
        print(json.dumps({**common, "impl": "ratio", "bt_manip_over_py_trees":
                          round(t_ours / t_theirs, 2)}))


if __name__ == "__main__":
    main()
