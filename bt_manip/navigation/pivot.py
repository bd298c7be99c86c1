"""Where a skid-steer base really turns about, learnt from its own motion while it turns.

A skid-steer base does not turn about its base frame: wheel scrub makes it pivot about a point
ahead of it. The descriptor gives that point for the bare robot (``base.pivot_offset``), but it
moves with the load and the arm's posture: the Husky turning on the spot pivots 0.11-0.18 m
ahead of its frame with the arm tucked, and 0.21-0.27 m ahead holding the 1.2 m panel after the
lift. A follower that steers a pivot point 0.12 m off the real one while turning on the spot
sees its target swing round as the base turns, and may circle the target without ever
reaching it.

:class:`PivotEstimate` watches the base from tick to tick. When the base turned by at least
:attr:`PivotEstimate.min_turn` and drove (by its last command) at most
:attr:`PivotEstimate.max_speed`, the point of the robot's x axis that stayed put is solved
from the two poses (after taking off the forward drive of the command), and the estimate moves
a fraction :attr:`PivotEstimate.gain` of the way to it, kept within
[:attr:`PivotEstimate.low`, :attr:`PivotEstimate.high`]. Other ticks leave it unchanged.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

Pose2D = tuple[float, float, float]


@dataclass
class PivotEstimate:
    """The pivot (m ahead of the base frame), starting at ``value`` and learnt while turning."""

    value: float
    low: float = -0.1
    """Smallest pivot (m) the estimate takes."""
    high: float = 0.5
    """Largest pivot (m) the estimate takes."""
    gain: float = 0.3
    """Fraction of the way to each measurement the estimate moves."""
    min_turn: float = 0.02
    """Smallest turn (rad) between two observations that is measured."""
    max_speed: float = 0.1
    """Largest commanded speed (m/s) between two observations that is measured: a turn on the
    spot, or nearly so."""
    measured: int = 0
    """How many measurements the estimate has taken in."""
    _last: tuple[Pose2D, float] | None = None
    _cmd: tuple[float, float] = (0.0, 0.0)

    def observe(self, pose: Pose2D, now: float) -> None:
        """Take the base pose at time ``now`` (s); measure the pivot from the move since the
        last observation when the base turned on the spot (see the module)."""
        last = self._last
        if last is not None and now <= last[1]:
            return  # the same tick again (a follower that took over within the tick)
        self._last = (pose, now)
        if last is None:
            return
        (x0, y0, th0), t0 = last
        x1, y1, th1 = pose
        dth = math.remainder(th1 - th0, math.tau)
        v = self._cmd[0]
        if abs(dth) < self.min_turn or abs(v) > self.max_speed:
            return
        # take off the forward drive along the mean heading
        mid = th0 + 0.5 * dth
        dx = x1 - x0 - v * (now - t0) * math.cos(mid)
        dy = y1 - y0 - v * (now - t0) * math.sin(mid)
        # the fixed point P (p ahead, q left in the robot frame) satisfies
        # B1 - B0 = (R(th0) - R(th1)) (p, q) = R(th0) (I - R(dth)) (p, q)
        c0, s0 = math.cos(th0), math.sin(th0)
        lx, ly = c0 * dx + s0 * dy, -s0 * dx + c0 * dy
        c, s = math.cos(dth), math.sin(dth)
        det = (1.0 - c) ** 2 + s * s
        p = ((1.0 - c) * lx - s * ly) / det
        p = min(self.high, max(self.low, p))
        self.value += self.gain * (p - self.value)
        self.measured += 1

    def sent(self, cmd: tuple[float, float]) -> None:
        """The twist (v, w) commanded until the next observation."""
        self._cmd = (float(cmd[0]), float(cmd[1]))
