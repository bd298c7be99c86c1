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

The registry also holds the *value types*: classes whose objects may be the value of a py_trees
behaviour's constructor argument in XML (py_trees' ``SetBlackboardVariable(variable_value=
Nested())``). XML never names a class to build: ``to_xml`` writes an object of a registered
class as its registered name and its attributes, and ``load_tree`` builds one only for a name
the loading program registered (see :mod:`bt_manip.bt.pytrees.values`)::

    registry.register_value_type(Nested)
"""

from __future__ import annotations

import enum
from collections.abc import Callable
from typing import Any, TypeVar, overload

import py_trees

from bt_manip.bt import py_trees_hook
from bt_manip.bt.node import BtNode

N = TypeVar("N", bound=type[Any])  # a BtNode or py_trees Behaviour subclass
V = TypeVar("V", bound=type[Any])  # a value type

SUBTREE_ID = "SubTree"

_NOT_PLAIN = (dict, list, tuple, set, frozenset, str, bytes, int, float, complex, enum.Enum)


class NodeRegistry:
    """Maps node IDs to node classes and remembers which are BT.CPP built-ins."""

    def __init__(self) -> None:
        self._classes: dict[str, type[BtNode]] = {}
        self._builtin: set[str] = set()
        self._value_types: dict[str, type[Any]] = {}

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
            _refuse_another(self._classes.get(node_id), node_cls, f"node ID '{node_id}'")
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

    @overload
    def register_value_type(self, cls: V, *, name: str | None = None) -> V: ...

    @overload
    def register_value_type(self, cls: None = None, *, name: str | None = None
                            ) -> Callable[[V], V]: ...

    def register_value_type(
        self, cls: V | None = None, *, name: str | None = None
    ) -> V | Callable[[V], V]:
        """Trust class ``cls`` as a value type under ``name`` (default: its ``__qualname__``);
        usable as a decorator. Its objects are written to XML as their attributes
        (``vars(obj)``) and built back without calling ``__init__``, as ``pickle`` does: register
        only a class whose attributes are the whole of its value.

        Raises TypeError for what is not a class whose objects keep a ``__dict__`` (or is a
        node class), ValueError when ``name`` is registered for another class."""

        def add(value_cls: V) -> V:
            if not isinstance(value_cls, type):
                raise TypeError(f"{value_cls!r} is not a class")
            if issubclass(value_cls, (BtNode, py_trees.behaviour.Behaviour)):
                raise TypeError(f"{value_cls.__qualname__} is a node class: register it with "
                                "registry.register")
            base = next((t for t in _NOT_PLAIN if issubclass(value_cls, t)), None)
            if base is not None:
                raise TypeError(f"{value_cls.__qualname__} subclasses {base.__name__}: only its "
                                "attributes would be written, not its contents")
            if not getattr(value_cls, "__dictoffset__", 0):
                raise TypeError(f"objects of {value_cls.__qualname__} keep no __dict__, so "
                                "their attributes cannot be written")
            key = value_cls.__qualname__ if name is None else name
            if not key or not isinstance(key, str):
                raise ValueError(f"a value type needs a non-empty name, got {key!r}")
            _refuse_another(self._value_types.get(key), value_cls, f"value type '{key}'")
            for other, registered in list(self._value_types.items()):
                if registered is value_cls and other != key:
                    del self._value_types[other]  # one name per class
            self._value_types[key] = value_cls
            return value_cls

        if cls is None:
            return add
        return add(cls)

    def unregister_value_type(self, name: str) -> None:
        self._value_types.pop(name, None)

    def value_type(self, name: str) -> type[Any] | None:
        """The class registered as value type ``name``, or None."""
        return self._value_types.get(name)

    def value_type_name(self, cls: type[Any]) -> str | None:
        """The name under which exactly ``cls`` (not a subclass) is a value type, or None."""
        for key, registered in self._value_types.items():
            if registered is cls:
                return key
        return None

    def value_types(self) -> dict[str, type[Any]]:
        """The registered value types by name (a copy)."""
        return dict(self._value_types)


def _refuse_another(existing: type | None, cls: type, what: str) -> None:
    """ValueError when ``what`` is registered for another class than ``cls`` (one of the same
    module and name, as a module imported again makes, is the same class)."""
    if existing is None or existing is cls:
        return
    if existing.__module__ == cls.__module__ and existing.__qualname__ == cls.__qualname__:
        return
    raise ValueError(f"{what} is already registered by "
                     f"{existing.__module__}.{existing.__qualname__}")


registry = NodeRegistry()
