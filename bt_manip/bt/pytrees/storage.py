"""py_trees' blackboard storage seen through a bt-manip blackboard.

Blackboard clients of a py_trees behaviour (``attach_blackboard_client()``, ports) read and
write the blackboard of the (sub)tree its node sits in, while the node runs: py_trees' absolute
key ``/foo`` and the relative ``foo`` both name entry ``foo`` (``/a/b`` names entry ``a/b``).
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterator, MutableMapping
from typing import Any

import py_trees

from bt_manip.bt.blackboard import Blackboard
from bt_manip.bt.node import TreeRuntimeError

PORT_PREFIX = "/__bt_manip_port__/"
"""py_trees key of a port that is not wired to an entry (kept by the leaf itself)."""


class EntryView(MutableMapping[str, Any]):
    """py_trees' key-value store seen through a bt-manip :class:`Blackboard`.

    ``/foo`` and ``foo`` are entry ``foo``; keys under :data:`PORT_PREFIX` live in ``local``.
    """

    def __init__(self, blackboard: Blackboard, local: dict[str, Any] | None = None) -> None:
        self.blackboard = blackboard
        self.local = local if local is not None else {}

    @staticmethod
    def entry(key: str) -> str:
        return key[1:] if key.startswith("/") else key

    def __getitem__(self, key: str) -> Any:
        if key.startswith(PORT_PREFIX):
            return self.local[key]
        return self.blackboard.get(self.entry(key))

    def __setitem__(self, key: str, value: Any) -> None:
        if key.startswith(PORT_PREFIX):
            self.local[key] = value
        else:
            self.blackboard.set(self.entry(key), value)

    def __delitem__(self, key: str) -> None:
        if key.startswith(PORT_PREFIX):
            del self.local[key]
            return
        name = self.entry(key)
        if not self.blackboard.has_value(name):
            raise KeyError(key)
        self.blackboard.unset(name)

    def __contains__(self, key: object) -> bool:
        if not isinstance(key, str):
            return False
        if key.startswith(PORT_PREFIX):
            return key in self.local
        return self.blackboard.has_value(self.entry(key))

    def __iter__(self) -> Iterator[str]:
        names = self.blackboard.keys()  # a bt-manip Blackboard, not a dict
        yield from ("/" + k for k in names)
        yield from self.local

    def __len__(self) -> int:
        return len(list(self.blackboard.keys())) + len(self.local)


@contextlib.contextmanager
def py_trees_storage(view: MutableMapping[str, Any]) -> Iterator[None]:
    """Make py_trees' blackboard clients use ``view`` while the block runs."""
    storage = py_trees.blackboard.Blackboard
    saved = storage.storage
    storage.storage = view  # type: ignore[assignment]  # py_trees types it dict; a mapping does
    try:
        yield
    finally:
        storage.storage = saved


@contextlib.contextmanager
def raised_as_tree_error(node: Any) -> Iterator[None]:
    """An exception raised by py_trees code (a behaviour's ``update()``...) becomes a
    :class:`TreeRuntimeError` naming the node, so a run ends with an error, not a traceback."""
    try:
        yield
    except TreeRuntimeError:
        raise
    except Exception as e:
        raise TreeRuntimeError(f"{node.describe()}: {type(e).__name__}: {e}") from e
