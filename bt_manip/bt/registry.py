"""The node registry: the single source of truth for node IDs.

Built-in BT.CPP nodes are registered when :mod:`bt_manip.bt` is imported; other nodes (robot
behaviours) register themselves when their module is imported::

    from bt_manip.bt import ActionNode, registry

    @registry.register
    class OpenGripper(ActionNode):
        ...

A py_trees behaviour class (any ``py_trees.behaviour.Behaviour`` subclass) can be registered
too: it is wrapped as a leaf (see :mod:`bt_manip.bt.pytrees.leaf`) under its class name, by
the py_trees adapter that importing :mod:`bt_manip.bt` installs
(:mod:`bt_manip.bt.py_trees_hook`).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, TypeVar, overload

import py_trees

from bt_manip.bt import py_trees_hook
from bt_manip.bt.node import BtNode

N = TypeVar("N", bound=type[Any])  # a BtNode or py_trees Behaviour subclass

SUBTREE_ID = "SubTree"


class NodeRegistry:
    """Maps node IDs to node classes and remembers which are BT.CPP built-ins."""

    def __init__(self) -> None:
        self._classes: dict[str, type[BtNode]] = {}
        self._builtin: set[str] = set()

    @overload
    def register(self, cls: N, *, builtin: bool = False) -> N: ...

    @overload
    def register(self, cls: None = None, *, builtin: bool = False) -> Callable[[N], N]: ...

    def register(
        self, cls: N | None = None, *, builtin: bool = False
    ) -> N | Callable[[N], N]:
        """Register ``cls`` under its ``NODE_ID``; usable as a decorator (with or without args)."""

        def add(node_cls: N) -> N:
            if isinstance(node_cls, type) and issubclass(node_cls, py_trees.behaviour.Behaviour) \
                    and not issubclass(node_cls, BtNode):
                leaf_class_for = py_trees_hook.adapter().leaf_class_for
                self.register(leaf_class_for(node_cls), builtin=builtin)
                return node_cls  # the user's class stays as it is
            if not (isinstance(node_cls, type) and issubclass(node_cls, BtNode)):
                raise TypeError(f"{node_cls!r} is neither a bt-manip node class nor a "
                                "py_trees.behaviour.Behaviour subclass")
            node_id = node_cls.NODE_ID
            existing = self._classes.get(node_id)
            if existing is not None and existing is not node_cls and not _same_origin(
                existing, node_cls
            ):
                raise ValueError(
                    f"node ID '{node_id}' is already registered by "
                    f"{existing.__module__}.{existing.__qualname__}"
                )
            self._classes[node_id] = node_cls
            if builtin:
                self._builtin.add(node_id)
            return node_cls

        if cls is None:
            return add
        return add(cls)

    def unregister(self, node_id: str) -> None:
        self._classes.pop(node_id, None)
        self._builtin.discard(node_id)

    def get(self, node_id: str) -> type[BtNode] | None:
        return self._classes.get(node_id)

    def __contains__(self, node_id: object) -> bool:
        return node_id in self._classes

    def is_builtin(self, node_id: str) -> bool:
        return node_id in self._builtin or node_id == SUBTREE_ID

    def ids(self) -> list[str]:
        return sorted(self._classes)

    def classes(self, builtin: bool | None = None) -> list[type[BtNode]]:
        """Registered classes sorted by ID; ``builtin`` True/False filters, None gives all."""
        out = []
        for node_id in sorted(self._classes):
            if builtin is None or (node_id in self._builtin) == builtin:
                out.append(self._classes[node_id])
        return out


def _same_origin(a: type, b: type) -> bool:
    return a.__module__ == b.__module__ and a.__qualname__ == b.__qualname__


registry = NodeRegistry()
