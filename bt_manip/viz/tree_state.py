"""The behaviour tree as the pages show it: its nodes once, then their statuses tick by tick.

:class:`TreeWatcher` walks a tree once with :func:`bt_manip.bt.walk.walk_nodes` (the order and
node IDs of the run report), keeps each node's name, node ID, depth and parent, and after every
tick reports which nodes changed status or reason. Statuses use BehaviorTree.CPP's names:
IDLE (py_trees' INVALID), RUNNING, SUCCESS, FAILURE.

What a node shows is its status while it runs and, once it has finished, what it last
returned: BehaviorTree.CPP (and py_trees) reset finished children to IDLE, but a failed leaf
must stay red beside its red parent. A node that was halted while RUNNING shows IDLE (see
:func:`bt_manip.bt.status.shown`). The last result of a bt-manip node is its ``last_status``;
for a plain py_trees tree it is what the watcher saw at the end of earlier ticks.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from bt_manip.bt.node import BtNode
from bt_manip.bt.status import STATUS_CODES, NodeStatus, as_status, shown, status_code
from bt_manip.bt.walk import walk_nodes

STATUS_NAMES = tuple(status.value for status in sorted(STATUS_CODES, key=STATUS_CODES.__getitem__))
"""Status names by their page code (:data:`bt_manip.bt.status.STATUS_CODES`)."""
IDLE = STATUS_CODES[NodeStatus.IDLE]


@dataclass(frozen=True)
class TreeNodeInfo:
    """A node's place in the tree."""

    index: int
    name: str
    node_id: str
    depth: int
    parent: int


@dataclass
class TreeWatcher:
    """Structure and current statuses of one tree (anything with a py_trees ``root``)."""

    tree: Any
    nodes: list[TreeNodeInfo] = field(default_factory=list)
    statuses: list[int] = field(default_factory=list)
    reasons: list[str] = field(default_factory=list)

    def __post_init__(self) -> None:
        self._behaviours: list[Any] = []
        self.nodes = []
        for walked in walk_nodes(self.tree.root):
            self.nodes.append(TreeNodeInfo(walked.index, walked.name, walked.node_id,
                                           walked.depth, walked.parent))
            self._behaviours.append(walked.node)
        self.statuses = [IDLE] * len(self.nodes)
        self.reasons = [""] * len(self.nodes)
        self._seen = [NodeStatus.IDLE] * len(self.nodes)  # status at the end of the last tick

    def structure(self) -> list[dict[str, Any]]:
        """The nodes as JSON-ready dicts (index, name, id, depth, parent)."""
        return [
            {"i": n.index, "name": n.name, "id": n.node_id, "depth": n.depth, "parent": n.parent}
            for n in self.nodes
        ]

    def _current(self) -> list[tuple[int, str]]:
        """(shown status, reason) of every node now."""
        out = []
        for i, b in enumerate(self._behaviours):
            if isinstance(b, BtNode):
                now, last = b.bt_status, b.last_status
            else:
                now = as_status(b.status)
                if now is not NodeStatus.IDLE or self._seen[i] is NodeStatus.RUNNING:
                    self._seen[i] = now  # a halted node forgets its result
                last = self._seen[i]
            out.append((status_code(shown(now, last)),
                        str(getattr(b, "feedback_message", "") or "")))
        return out

    def update(self) -> list[tuple[int, int, str]]:
        """Read the statuses now; return the changes as (node index, status code, reason)."""
        changes = []
        for i, (code, reason) in enumerate(self._current()):
            if code != self.statuses[i] or reason != self.reasons[i]:
                self.statuses[i] = code
                self.reasons[i] = reason
                changes.append((i, code, reason))
        return changes


def shown_status(status: int, last: int) -> int:
    """What a page shows (a code) for a node with code ``status`` now that last returned
    ``last`` (see :func:`bt_manip.bt.status.shown`)."""
    return status_code(shown(as_status(status), as_status(last)))


def run_result(watcher: TreeWatcher) -> str:
    """'SUCCESS' or 'FAILURE' once the last tick finished the tree, else ''.

    Read from the tree's last tick result (``bt_status``): a root that finished is reset to
    IDLE by the tick, as in BehaviorTree.CPP, so its node status no longer shows it.
    """
    status = getattr(watcher.tree, "bt_status", None)
    name = getattr(status, "name", None)
    if name is None:
        name = STATUS_NAMES[watcher.statuses[0]] if watcher.statuses else ""
    return name if name in ("SUCCESS", "FAILURE") else ""
