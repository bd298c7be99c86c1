"""How much of a run's wall time numba spent compiling bt-manip's kernels.

The navigation searches and a few geometry loops are compiled by numba the first time they run
after an install (tens of seconds for a whole Navigate) and stored in its cache; later
processes load them in a fraction of a second. A first run's wall time, and its real-time
factor, therefore say little about the runs after it: the report gives the part spent in numba
separately (``jit_time``), and the summary names it when it is worth a mention.
"""

from __future__ import annotations

from types import TracebackType

from numba.core import event

JIT_NOTE_S = 1.0
"""Seconds of compiling from which the summary mentions it."""


class JitClock:
    """A context manager timing numba's compile events (its outermost ones: a kernel that
    compiles the helpers it calls counts once) while the block runs.

    Loading a kernel from numba's cache is one of those events too; it takes milliseconds.
    ``seconds`` is the total so far, 0.0 when nothing was compiled or loaded."""

    def __init__(self) -> None:
        self._listener = event.TimingListener()

    def __enter__(self) -> JitClock:
        event.register("numba:compile", self._listener)
        return self

    def __exit__(self, kind: type[BaseException] | None, exc: BaseException | None,
                 tb: TracebackType | None) -> None:
        event.unregister("numba:compile", self._listener)

    @property
    def seconds(self) -> float:
        return float(self._listener.duration) if self._listener.done else 0.0
