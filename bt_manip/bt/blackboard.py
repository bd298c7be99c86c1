"""Blackboards with BehaviorTree.CPP scoping.

Every tree (the main tree and each SubTree instance) has its own :class:`Blackboard`. A SubTree's
blackboard sees its parent's entries only through explicit remapping (``port="{parent_key}"``)
or, with ``_autoremap``, through every key that does not start with ``_``. A key written as
``@key`` always addresses the root blackboard. There is no global state: each loaded tree owns
its blackboards.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from typing import Any


class Blackboard:
    """A key/value store with an optional parent, remapping table and auto-remapping."""

    def __init__(
        self,
        parent: Blackboard | None = None,
        remap: dict[str, str] | None = None,
        autoremap: bool = False,
    ) -> None:
        self.parent = parent
        self.remap: dict[str, str] = dict(remap or {})
        self.autoremap = autoremap
        self._data: dict[str, Any] = {}

    @classmethod
    def from_dict(cls, values: dict[str, Any] | None) -> Blackboard:
        bb = cls()
        for key, value in (values or {}).items():
            bb.set(key, value)
        return bb

    def root(self) -> Blackboard:
        bb = self
        while bb.parent is not None:
            bb = bb.parent
        return bb

    def _owner(self, key: str) -> tuple[Blackboard, str]:
        """Return the blackboard that stores ``key`` and the key's name there."""
        bb = self
        while True:
            if key.startswith("@"):
                return bb.root(), key[1:]
            if key in bb._data or bb.parent is None:
                return bb, key
            if key in bb.remap:
                key = bb.remap[key]
                bb = bb.parent
                continue
            if bb.autoremap and not key.startswith("_"):
                bb = bb.parent
                continue
            return bb, key

    def exists(self, key: str) -> bool:
        bb, name = self._owner(key)
        return name in bb._data

    def get(self, key: str) -> Any:
        """Value of ``key``; raises KeyError when the entry does not exist."""
        bb, name = self._owner(key)
        return bb._data[name]

    def get_or(self, key: str, default: Any = None) -> Any:
        bb, name = self._owner(key)
        return bb._data.get(name, default)

    def set(self, key: str, value: Any) -> None:
        bb, name = self._owner(key)
        bb._data[name] = value

    def unset(self, key: str) -> None:
        bb, name = self._owner(key)
        bb._data.pop(name, None)

    def keys(self) -> Iterator[str]:
        """Keys stored in this blackboard itself (not those reached through the parent)."""
        return iter(list(self._data))

    def as_dict(self) -> dict[str, Any]:
        """The entries of this blackboard as a JSON-serialisable dict."""
        return {key: _jsonable(value) for key, value in sorted(self._data.items())}

    def __repr__(self) -> str:
        return f"Blackboard({self._data!r})"


def _jsonable(value: Any) -> Any:
    if value is None or isinstance(value, (bool, int, str)):
        return value
    if isinstance(value, float):
        return value if math.isfinite(value) else str(value)
    if isinstance(value, dict):
        return {str(k): _jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_jsonable(v) for v in value]
    tolist = getattr(value, "tolist", None)
    if callable(tolist):
        return _jsonable(tolist())
    if hasattr(value, "value") and hasattr(value, "name"):  # enums
        return str(value.name)
    return str(value)
