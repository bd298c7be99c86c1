"""How often each node of a run was ticked and what it returned: :class:`NodeCounter`.

The counter is the tree context's ``observer`` (:class:`~bt_manip.bt.context.TickObserver`)
while a run lasts: every tick of a node adds to its ``ticks`` and to the count of the status it
returned (``success``, ``failure``, ``skipped``; RUNNING only counts as a tick), and every halt
of a node that was RUNNING adds to its ``halted`` (a parent stopped it, or the run ended on a
budget or an interruption). Nodes are named by their path (:func:`bt_manip.bt.walk.walk_nodes`),
so the two instances of a SubTree count apart.

The :class:`~bt_manip.run.runner.Runner` keeps one per run; the run report carries the counts of
each node (``counts``), and a bench sums them over its episodes (:mod:`bt_manip.bench.coverage`).
"""

from __future__ import annotations

from typing import Any

from bt_manip.bt.node import BtNode
from bt_manip.bt.status import NodeStatus
from bt_manip.bt.walk import walk_nodes

COUNT_FIELDS = ("ticks", "success", "failure", "skipped", "halted")
"""The counts kept per node, in the order of a node's count list."""
_OF_STATUS = {NodeStatus.SUCCESS: 1, NodeStatus.FAILURE: 2, NodeStatus.SKIPPED: 3}
_HALTED = 4


class NodeCounter:
    """Counts, per node path, the ticks and results of ``tree``'s nodes while it is attached
    (see the module docstring); a list of :data:`COUNT_FIELDS` per node ever ticked."""

    def __init__(self, tree: Any) -> None:
        self.tree = tree
        self.paths: dict[int, str] = {id(w.node): w.path for w in walk_nodes(tree.root)}
        self.counts: dict[str, list[int]] = {}

    @staticmethod
    def can_watch(tree: Any) -> bool:
        """Whether ``tree`` is a bt-manip tree: its root a bt-manip node, its context one that
        tells an observer of its ticks (the nodes of a plain py_trees tree tell nobody)."""
        return (isinstance(getattr(tree, "root", None), BtNode)
                and hasattr(getattr(tree, "context", None), "observer"))

    def attach(self) -> NodeCounter:
        """Start counting: become the tree context's observer."""
        self.tree.context.observer = self
        return self

    def detach(self) -> None:
        """Stop counting (the counts stay)."""
        if self.tree.context.observer is self:
            self.tree.context.observer = None

    def _row(self, node: Any) -> list[int] | None:
        path = self.paths.get(id(node))
        if path is None:
            return None
        row = self.counts.get(path)
        if row is None:
            row = self.counts[path] = [0] * len(COUNT_FIELDS)
        return row

    def result(self, node: Any, status: NodeStatus) -> None:
        row = self._row(node)
        if row is not None:
            row[0] += 1
            index = _OF_STATUS.get(status)
            if index is not None:
                row[index] += 1

    def halted(self, node: Any) -> None:
        row = self._row(node)
        if row is not None:
            row[_HALTED] += 1

    def of(self, path: str) -> dict[str, int]:
        """The counts of the node at ``path``, by name (zeros for a node never ticked)."""
        row = self.counts.get(path) or [0] * len(COUNT_FIELDS)
        return dict(zip(COUNT_FIELDS, row, strict=True))
