"""What a tree's nodes can reach besides the blackboard: the clock, the world, the timers.

A run adds its services (fault injector, overlay, each robot's navigator and IK) in
:class:`bt_manip.run_context.RunContext`, a subclass.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Protocol

from bt_manip.clock import Clock, MonotonicClock

if TYPE_CHECKING:
    from bt_manip.bt.status import NodeStatus

TIME_EPS = 1e-9  # seconds: tolerance when comparing clock readings


class TickObserver(Protocol):
    """What a tree tells its context's ``observer`` as it runs."""

    def result(self, node: Any, status: NodeStatus) -> None:
        """``node`` was ticked and returned ``status`` (RUNNING, SUCCESS, FAILURE, SKIPPED)."""
        ...

    def halted(self, node: Any) -> None:
        """``node`` was halted while RUNNING."""
        ...


@dataclass
class TreeContext:
    """Shared by every node of one tree.

    ``clock`` is what every duration (Timeout, Delay, Sleep, controller time-outs) reads: the
    world's simulation clock when a world is loaded, the monotonic clock otherwise. ``world`` is
    the loaded world or None.
    """

    clock: Clock = field(default_factory=MonotonicClock)
    world: Any = None
    wake_up: bool = False
    """A node asked for the root to be ticked again (BT.CPP's wake-up signal)."""
    timers: dict[int, tuple[float, Callable[[], None] | None]] = field(default_factory=dict)
    """Pending timers of Sleep, Delay and Timeout: id -> (deadline, callback)."""
    _timer_ids: int = 0
    visited: list[Any] | None = None
    """Nodes ticked in the current tree tick, in the order they returned (set by Tree)."""
    tree: Any = None
    """The Tree that ticks this context (for py_trees tools ticking the root)."""
    observer: TickObserver | None = None
    """Told of every node's tick result and of every halt of a RUNNING node (the run's
    :class:`~bt_manip.run.coverage.NodeCounter`); None costs nothing."""

    def now(self) -> float:
        return self.clock.now()

    def start_timer(self, seconds: float, callback: Callable[[], None] | None = None) -> int:
        """A timer on the tree's clock, as BT.CPP's timer queue (which runs on its own thread).

        When ``seconds`` have passed, ``callback`` runs and the wake-up signal is emitted.
        Timers fire at the start of each ``Tree.tick()`` and before each re-tick of its wake-up
        loop (or at once when ``seconds`` <= 0); the sim clock only moves between ticks, the
        wall clock also within one. Returns an id for :meth:`cancel_timer`.
        """
        self._timer_ids += 1
        if seconds <= 0:
            if callback is not None:
                callback()
            self.wake_up = True
        else:
            self.timers[self._timer_ids] = (self.clock.now() + seconds, callback)
        return self._timer_ids

    def cancel_timer(self, timer: int | None) -> None:
        """Forget a timer (it neither calls back nor wakes the tree up)."""
        if timer is not None:
            self.timers.pop(timer, None)

    def fire_timers(self) -> None:
        """Run the timers whose time has come, in deadline order."""
        now = self.clock.now() + TIME_EPS
        due = sorted((deadline, timer) for timer, (deadline, _) in self.timers.items()
                     if deadline <= now)
        for _, timer in due:
            _, callback = self.timers.pop(timer)
            if callback is not None:
                callback()
            self.wake_up = True
