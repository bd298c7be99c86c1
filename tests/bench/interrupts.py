"""An interrupted bench, for the tests of resuming one: the episode runner raises
KeyboardInterrupt (as Ctrl-C would) for the episodes ``stop`` picks."""

from __future__ import annotations

from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import Any

import pytest

from bt_manip.bench import pool


@contextmanager
def interrupted_when(monkeypatch: pytest.MonkeyPatch,
                     stop: Callable[[Any], bool]) -> Iterator[None]:
    """Within the block, an episode whose spec ``stop`` picks is interrupted; after it, every
    episode runs again."""
    real_run_one = pool.run_one

    def run_one(spec: Any) -> Any:
        if stop(spec):
            raise KeyboardInterrupt
        return real_run_one(spec)

    monkeypatch.setattr(pool, "run_one", run_one)
    try:
        yield
    finally:
        monkeypatch.setattr(pool, "run_one", real_run_one)
