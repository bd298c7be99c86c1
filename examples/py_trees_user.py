"""Coming from py_trees: your behaviours, your tree and your tools, run by bt-manip.

A py_trees tree (py_trees' composites and decorators, its own leaves and a behaviour of ours
with a blackboard client) is converted with ``from_py_trees`` and ticked through py_trees'
own ``BehaviourTree`` with a ``SnapshotVisitor``: after each tick the tree is printed with
``py_trees.display.unicode_tree``. The clock is a manual one, moved 0.1 s per tick, as the
simulation clock would be under ``bt-manip run --world``.

    python examples/py_trees_user.py          # tick until the root finishes, showing each tick
    python examples/py_trees_user.py --xml    # the converted tree as BT.CPP v4 XML for Groot2
"""

from __future__ import annotations

import argparse

import py_trees
from py_trees.common import Access, Status

from bt_manip.bt import Tree, TreeContext, from_py_trees, registry, to_xml
from bt_manip.clock import ManualClock


class CountDown(py_trees.behaviour.Behaviour):
    """RUNNING while it counts ``start`` down to zero, then SUCCESS; writes the count to
    ``/count`` (entry ``count`` of the bt-manip blackboard)."""

    def __init__(self, name: str, start: int = 3) -> None:
        super().__init__(name)
        self.start = start
        self.left = start
        self.client = self.attach_blackboard_client()
        self.client.register_key("/count", access=Access.WRITE)

    def initialise(self) -> None:
        self.left = self.start

    def update(self) -> Status:
        self.left -= 1
        self.client.count = self.left
        self.feedback_message = f"{self.left} to go"
        return Status.SUCCESS if self.left <= 0 else Status.RUNNING


registry.register(CountDown)  # also usable as <CountDown start="5"/> in XML files


def build() -> py_trees.behaviour.Behaviour:
    """The task, written with py_trees only."""
    b = py_trees.behaviours
    warm_up = py_trees.decorators.Repeat(
        "warm up twice", py_trees.composites.Sequence("warm up", memory=True, children=[
            CountDown("count down", start=2),
            b.SetBlackboardVariable("mark warm", "warm", True, overwrite=True),
        ]), num_success=2)
    retry = py_trees.decorators.Retry("retry", b.SuccessEveryN("every third", 3), 3)
    wait = py_trees.decorators.Timeout("at most 1 s", py_trees.timers.Timer("wait", 0.35), 1.0)
    return py_trees.composites.Sequence("task", memory=True, children=[
        warm_up,
        py_trees.composites.Parallel(
            "together", py_trees.common.ParallelPolicy.SuccessOnAll(), children=[retry, wait]),
    ])


def run(show: bool = True) -> tuple[Tree, list[str]]:
    """Tick the converted tree until its root finishes; returns it and the root statuses."""
    clock = ManualClock()
    tree = from_py_trees(build(), context=TreeContext(clock=clock))
    behaviour_tree = py_trees.trees.BehaviourTree(tree.root)
    snapshot = py_trees.visitors.SnapshotVisitor()
    behaviour_tree.add_visitor(snapshot)

    def show_tick(bt: py_trees.trees.BehaviourTree) -> None:
        if show:
            print(f"--- tick {bt.count + 1} (t = {clock.now():.1f} s)")
            print(py_trees.display.unicode_tree(bt.root, show_status=True))

    behaviour_tree.add_post_tick_handler(show_tick)
    statuses: list[str] = []
    while not statuses or statuses[-1] == "RUNNING":
        behaviour_tree.tick()
        statuses.append(tree.bt_status.value)
        clock.advance(0.1)
    if show:
        print("result:", statuses[-1], "blackboard:", tree.blackboard.as_dict())
    return tree, statuses


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--xml", action="store_true", help="print the tree as XML and exit")
    args = parser.parse_args()
    if args.xml:
        print(to_xml(from_py_trees(build())))
        return
    run()


if __name__ == "__main__":
    main()
