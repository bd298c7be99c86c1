"""What bt-manip keeps to reuse: files it builds once (composed URDFs, compiled IK code) in a
cache folder, and results a process computes again and again (:class:`Memo`).

A :class:`Memo` maps keys that hold every input of a computation (the bytes of its numbers or
of a file, long ones as their digest, see :func:`bytes_key`; a file's size, modification time
and inode where the file itself is not read) to its result, so a result taken from it is the
one the computation would give. It is bounded and drops the least recently used entry first.
What it holds must not be changed by those who read it: frozen dataclasses, tuples, read-only
arrays, or copies handed out.
"""

from __future__ import annotations

import hashlib
import os
import threading
from collections.abc import Hashable
from pathlib import Path
from typing import Generic, TypeVar

V = TypeVar("V")


def cache_dir(kind: str, override: str) -> Path:
    """``$<override>`` if set, else ``$XDG_CACHE_HOME/bt-manip/<kind>`` (``~/.cache`` by
    default). The folder is not created here."""
    env = os.environ.get(override)
    if env:
        return Path(env)
    xdg = os.environ.get("XDG_CACHE_HOME")
    root = Path(xdg) if xdg else Path.home() / ".cache"
    return root / "bt-manip" / kind


SHORT_KEY_BYTES = 256
"""Keys up to this long are kept as they are; longer ones as their digest."""


def bytes_key(data: bytes) -> bytes:
    """A memo key for ``data``: ``data`` itself when short, else its 256-bit BLAKE2b digest
    (so that a key stays small however large what it stands for; two different inputs with
    one digest are not expected ever to be met). The two kinds never equal each other."""
    if len(data) <= SHORT_KEY_BYTES:
        return b"=" + data
    return b"#" + hashlib.blake2b(data, digest_size=32).digest()


class Memo(Generic[V]):
    """Results by key, at most ``max_entries`` of them, the least recently used dropped
    first; safe to use from several threads. ``get`` answers ``None`` for a key not held, so
    a result that may be ``None`` is stored wrapped (in a tuple, say)."""

    def __init__(self, max_entries: int) -> None:
        self.max_entries = max_entries
        self._items: dict[Hashable, V] = {}
        self._lock = threading.Lock()

    def get(self, key: Hashable) -> V | None:
        """The result stored under ``key`` (now the most recently used), or None."""
        with self._lock:
            value = self._items.pop(key, None)
            if value is not None:
                self._items[key] = value
            return value

    def put(self, key: Hashable, value: V) -> None:
        """Store ``value`` under ``key``, dropping the oldest entries beyond the bound."""
        with self._lock:
            self._items.pop(key, None)
            while self._items and len(self._items) >= self.max_entries:
                del self._items[next(iter(self._items))]
            if self.max_entries > 0:
                self._items[key] = value

    def clear(self) -> None:
        with self._lock:
            self._items.clear()

    def __len__(self) -> int:
        return len(self._items)
