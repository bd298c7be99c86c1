"""The one tree walk: every node of a tree with its place, as reports, consoles and pages show it.

:func:`walk_nodes` visits a tree depth first, parents before children, and gives each node its
index in that order, its path, depth, parent index and node ID. It takes a bt-manip
:class:`~bt_manip.bt.node.BtNode` root (children from ``bt_children()``, so a SubTree's tree
shows under it) or a plain py_trees root (children from ``children``): the only place that tells
the two apart.

Naming, the same in the run report, the console and the pages:

- ``path``: the names from the root joined by '/'; a name that repeats among siblings gets
  ``#2``, ``#3``... so that every path is unique.
- ``node_id``: the node's registered ID (``NODE_ID``), the tree ID for a SubTree (as Groot2 and
  the BT.CPP loggers show it), and the class name for a plain py_trees behaviour.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass
from typing import Any

from bt_manip.bt.node import BtNode
from bt_manip.bt.subtree import SubTree


@dataclass(frozen=True)
class WalkedNode:
    """A node and its place in the tree (see :func:`walk_nodes`)."""

    index: int
    path: str
    depth: int
    parent: int
    name: str
    node_id: str
    node: Any


def children_of(node: Any) -> list[Any]:
    """The node's children: ``bt_children()`` for bt-manip nodes, ``children`` for py_trees."""
    if isinstance(node, BtNode):
        return node.bt_children()
    return list(getattr(node, "children", None) or [])


def node_id_of(node: Any) -> str:
    """The ID a report or page shows for ``node`` (the tree ID for a SubTree)."""
    if isinstance(node, SubTree):
        return node.tree_id
    if isinstance(node, BtNode):
        return node.NODE_ID
    return str(getattr(node, "node_id", None) or type(node).__name__)


def walk_nodes(root: Any) -> Iterator[WalkedNode]:
    """Every node under ``root`` (included), depth first, parents before children."""
    counter = 0
    stack: list[tuple[Any, str, int, int]] = [(root, str(root.name), 0, -1)]
    while stack:
        node, path, depth, parent = stack.pop()
        index = counter
        counter += 1
        yield WalkedNode(index, path, depth, parent, str(node.name), node_id_of(node), node)
        seen: dict[str, int] = {}
        below = []
        for child in children_of(node):
            name = str(child.name)
            count = seen.get(name, 0) + 1
            seen[name] = count
            suffix = f"#{count}" if count > 1 else ""
            below.append((child, f"{path}/{name}{suffix}", depth + 1, index))
        stack.extend(reversed(below))
