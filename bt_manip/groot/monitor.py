"""Status changes of a tree, stamped with the run's time (BT.CPP's StatusChangeLogger).

A :class:`TreeMonitor` subscribes to every node of a tree (subtrees included) and calls its
consumers with ``(uid, previous, new, time_us)`` at each change of a node's status, in the
order they happen. ``time_us`` is the run's time in microseconds since the monitor started:
the world's sim clock when there is a world, so a replay shows the run at its own pace.

Nodes keep their status in a plain attribute, so that an unwatched tree pays nothing;
:func:`watch` moves a node to a subclass of its own class whose ``bt_status`` is a property
telling the listeners of every change, and :func:`unwatch` moves it back.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from typing import cast

from bt_manip.bt.node import BtNode
from bt_manip.bt.status import NodeStatus
from bt_manip.bt.tree import Tree
from bt_manip.groot.layout import TreeLayout, layout_of

Consumer = Callable[[int, NodeStatus, NodeStatus, int], None]
Listener = Callable[[BtNode, NodeStatus, NodeStatus], None]

_WATCHED_CLASSES: dict[type, type] = {}
_STATUS = "_watched_status"
_LISTENERS = "_status_listeners"


def _get_status(node: BtNode) -> NodeStatus:
    return cast(NodeStatus, node.__dict__[_STATUS])


def _set_status(node: BtNode, value: NodeStatus) -> None:
    data = node.__dict__
    previous = data[_STATUS]
    data[_STATUS] = value
    if value is not previous:
        for listener in data[_LISTENERS]:
            listener(node, previous, value)


def _watched_class(cls: type) -> type:
    watched = _WATCHED_CLASSES.get(cls)
    if watched is None:
        watched = type(cls.__name__, (cls,), {
            "bt_status": property(_get_status, _set_status),
            "NODE_ID": getattr(cls, "NODE_ID", cls.__name__),
            "__module__": cls.__module__,
            "__qualname__": cls.__qualname__,
            "_unwatched_class": cls,
        })
        _WATCHED_CLASSES[cls] = watched
    return watched


def watch(node: BtNode, listener: Listener) -> None:
    """Call ``listener(node, previous, new)`` at each change of ``node.bt_status``."""
    data = node.__dict__
    if _LISTENERS not in data:
        data[_STATUS] = data.pop("bt_status")
        data[_LISTENERS] = []
        node.__class__ = _watched_class(type(node))
    data[_LISTENERS].append(listener)


def unwatch(node: BtNode, listener: Listener) -> None:
    """Stop calling ``listener``; a node nobody watches gets its own class back."""
    data = node.__dict__
    listeners = data.get(_LISTENERS)
    if listeners is None or listener not in listeners:
        return
    listeners.remove(listener)
    if not listeners:
        node.__class__ = type(node)._unwatched_class  # type: ignore[attr-defined]
        del data[_LISTENERS]
        data["bt_status"] = data.pop(_STATUS)


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
            watch(node, self._changed)

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
            unwatch(node, self._changed)
        self.consumers.clear()
