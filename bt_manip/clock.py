"""Clocks that behaviour-tree durations read.

Every duration in a tree (Timeout, Delay, Sleep, controller time-outs) asks a :class:`Clock`
for the time. When a world is loaded the clock is the world's simulation clock, so a headless
run is as fast as physics allows and repeatable; without a world it is the monotonic clock.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Protocol, runtime_checkable


@runtime_checkable
class Clock(Protocol):
    """Anything that tells the current time in seconds."""

    def now(self) -> float:
        """Return the current time in seconds (only differences are meaningful)."""
        ...


class MonotonicClock:
    """Wall clock for runs without a world: ``time.monotonic()``."""

    def now(self) -> float:
        return time.monotonic()


@dataclass
class ManualClock:
    """A clock that moves only when told to; used by the sim and by tests."""

    t: float = 0.0

    def now(self) -> float:
        return self.t

    def advance(self, dt: float) -> None:
        """Move the clock forward by ``dt`` seconds (``dt`` >= 0)."""
        if dt < 0:
            raise ValueError("a clock cannot go backwards")
        self.t += dt
