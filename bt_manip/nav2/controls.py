"""Nav2's control nodes: PipelineSequence, RecoveryNode and RoundRobin.

They follow Nav2's ``nav2_behavior_tree`` plugins tick for tick. "Halt" of a child means: a
RUNNING child is halted (its ``terminate(INVALID)`` runs once) and it goes back to IDLE; a child
that finished is only set back to IDLE.
"""

from __future__ import annotations

import sys
from typing import Any

from py_trees.ports import PortInformation

from bt_manip.bt.node import BtNode, ControlNode
from bt_manip.bt.ports import Accepts, Port
from bt_manip.bt.registry import registry
from bt_manip.bt.status import NodeStatus

RUNNING = NodeStatus.RUNNING
SUCCESS = NodeStatus.SUCCESS
FAILURE = NodeStatus.FAILURE
SKIPPED = NodeStatus.SKIPPED


@registry.register
class PipelineSequence(ControlNode):
    """Ticks its children in order, re-ticking every child it has already reached.

    Each tick starts at the first child and goes on while children succeed, or are RUNNING but
    lie before the furthest child reached so far (so an earlier child, such as a rate-limited
    planner, keeps running alongside a later one, such as the controller):

    - child FAILURE: halt every child and return FAILURE;
    - child RUNNING at or beyond the furthest child reached: remember it, return RUNNING;
    - child SUCCESS (or SKIPPED, or RUNNING before the furthest child): go on to the next one.

    When the last child succeeds, every child is halted and it returns SUCCESS (SKIPPED when
    every child was skipped).
    """

    def __init__(self, name: str | None = None, children: list[BtNode] | None = None,
                 **attributes: Any) -> None:
        super().__init__(name, children, **attributes)
        self.last_child_ticked = 0

    def tick_node(self) -> NodeStatus:
        self.set_running()
        skipped = 0
        for index, child in enumerate(self.bt_children()):
            status = child.execute_tick()
            if status is FAILURE:
                self.halt()
                return FAILURE
            if status is RUNNING and index >= self.last_child_ticked:
                self.last_child_ticked = index
                return RUNNING
            if status is SKIPPED:
                skipped += 1
        all_skipped = skipped == len(self.children)
        self.halt()
        return SKIPPED if all_skipped else SUCCESS

    def halt(self) -> None:
        self.last_child_ticked = 0
        super().halt()


@registry.register
class RecoveryNode(ControlNode):
    """Runs its first child; when it fails, runs the second (the recovery) and tries again.

    Exactly two children. First child:

    - SUCCESS: halt both, return SUCCESS;
    - RUNNING: return RUNNING;
    - SKIPPED: halt both, return SKIPPED;
    - FAILURE: with retries left, halt it and tick the recovery in the same tick; otherwise
      halt both and return FAILURE.

    Recovery child:

    - SUCCESS: halt it, count one retry and tick the first child again in the same tick;
    - RUNNING: return RUNNING;
    - FAILURE: halt both, return FAILURE;
    - SKIPPED: no recovery is possible: halt it and return FAILURE (not counted as a retry).

    Halting resets the retry count. ``number_of_retries="-1"`` sets no limit: the first child
    is tried again after every successful recovery (Nav2's trees with a RecoveryManager, which
    decides when recovering is over, write it so). Without a limit, after
    :attr:`RETRIES_PER_TICK` retries in one tick it returns RUNNING and goes on at the next
    tick, so that two children that fail and recover at once cannot hold a tick forever.
    """

    RETRIES_PER_TICK = 100

    MIN_CHILDREN = 2
    MAX_CHILDREN = 2
    INPUT_PORTS: dict[str, PortInformation] = {
        "number_of_retries": Port(int, False, "Number of retries (-1: no limit)", 1,
                                  Accepts(low=0, also=(-1,))),
    }

    def __init__(self, name: str | None = None, children: list[BtNode] | None = None,
                 **attributes: Any) -> None:
        super().__init__(name, children, **attributes)
        self.current = 0
        self.retries = 0

    def tick_node(self) -> NodeStatus:
        allowed = int(self.get_input("number_of_retries"))
        unlimited = allowed < 0
        if unlimited:
            allowed = sys.maxsize
        this_tick = 0
        self.set_running()
        while self.retries <= allowed:
            status = self.bt_children()[self.current].execute_tick()
            if self.current == 0:
                if status is RUNNING:
                    return RUNNING
                if status is SUCCESS or status is SKIPPED:
                    self.halt()
                    return status
                if self.retries >= allowed:
                    self.halt()
                    return FAILURE
                self.halt_child(0)
                self.current = 1
            else:
                if status is RUNNING:
                    return RUNNING
                if status is SKIPPED:
                    self.current = 0
                    self.halt_child(1)
                    return FAILURE
                if status is FAILURE:
                    self.halt()
                    return FAILURE
                self.halt_child(1)
                self.retries += 1
                self.current = 0
                this_tick += 1
                if unlimited and this_tick >= self.RETRIES_PER_TICK:
                    return RUNNING
        self.halt()
        return FAILURE

    def halt(self) -> None:
        self.current = 0
        self.retries = 0
        super().halt()


@registry.register
class RoundRobin(ControlNode):
    """Ticks one child per activation, moving to the next child each time one finishes.

    - child SUCCESS: the next activation starts at the following child (wrapping round);
      halt every child and return SUCCESS;
    - child FAILURE (or SKIPPED): try the following child in the same tick;
    - child RUNNING: return RUNNING; the next tick resumes it.

    When every child failed (or was skipped) in a row it returns FAILURE (SKIPPED when all were
    skipped). Where it stands is kept between activations, so recoveries take turns; halting
    it while a child runs sends it back to the first child.
    """

    def __init__(self, name: str | None = None, children: list[BtNode] | None = None,
                 **attributes: Any) -> None:
        super().__init__(name, children, **attributes)
        self.current = 0
        self.failed = 0

    def tick_node(self) -> NodeStatus:
        kids = self.bt_children()
        n = len(kids)
        self.set_running()
        skipped = 0
        while self.failed + skipped < n:
            status = kids[self.current].execute_tick()
            if status is not RUNNING:
                self.current = (self.current + 1) % n
            if status is SUCCESS:
                self.failed = 0
                self.reset_children()
                return SUCCESS
            if status is RUNNING:
                return RUNNING
            if status is FAILURE:
                self.failed += 1
            else:
                skipped += 1
        all_skipped = skipped == n
        self.halt()
        self.failed = 0
        return SKIPPED if all_skipped else FAILURE

    def halt(self) -> None:
        self.current = 0
        self.failed = 0
        super().halt()
