"""Status changes of a tree, stamped with the run's time (BT.CPP's StatusChangeLogger).

A :class:`TreeMonitor` subscribes to every node of a tree (subtrees included) and calls its
consumers with ``(uid, previous, new, time_us)`` at each change of a node's status, in the
order they happen. ``time_us`` is the run's time in microseconds since the monitor started:
the world's sim clock when there is a world, so a replay shows the run at its own pace.
"""

from __future__ import annotations

import threading
from collections.abc import Callable

from bt_manip.bt.node import BtNode
from bt_manip.bt.status import NodeStatus
from bt_manip.bt.tree import Tree
from bt_manip.groot.layout import TreeLayout, layout_of

Consumer = Callable[[int, NodeStatus, NodeStatus, int], None]


class TreeMonitor:
    """Watches the status changes of ``tree``; ``now`` gives the run's clock in seconds."""

    def __init__(self, tree: Tree, now: Callable[[], float]) -> None:
        self.tree = tree
        self.layout: TreeLayout = layout_of(tree)
        self._now = now
        self._start = now()
        self.consumers: list[Consumer] = []
        self.lock = threading.Lock()
        """Held while consumers run: readers on other threads take it for a consistent view."""
        for node in self.layout.nodes_by_uid.values():
            node.status_listeners = (*node.status_listeners, self._changed)

    def time_us(self) -> int:
        """Microseconds of run time since the monitor started."""
        return round((self._now() - self._start) * 1e6)

    def _changed(self, node: BtNode, previous: NodeStatus, new: NodeStatus) -> None:
        uid = self.layout.uid_of.get(id(node))
        if uid is None:
            return
        stamp = self.time_us()
        with self.lock:
            for consumer in self.consumers:
                consumer(uid, previous, new, stamp)

    def close(self) -> None:
        """Stop listening to the tree."""
        for node in self.layout.nodes_by_uid.values():
            node.status_listeners = tuple(
                fn for fn in node.status_listeners if fn != self._changed)
        self.consumers.clear()
