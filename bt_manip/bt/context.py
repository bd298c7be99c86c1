"""What a tree's nodes can reach besides the blackboard: the clock, the world, services."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from bt_manip.clock import Clock, MonotonicClock


@dataclass
class TreeContext:
    """Shared by every node of one tree.

    ``clock`` is what every duration (Timeout, Delay, Sleep, controller time-outs) reads: the
    world's simulation clock when a world is loaded, the monotonic clock otherwise. ``world`` is
    the loaded world or None; ``services`` holds named helpers that robot behaviours look up.
    """

    clock: Clock = field(default_factory=MonotonicClock)
    world: Any = None
    services: dict[str, Any] = field(default_factory=dict)
    wake_up: bool = False
    """A node asked for the root to be ticked again (BT.CPP's wake-up signal)."""

    def now(self) -> float:
        return self.clock.now()
