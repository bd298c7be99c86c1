"""Nav2's decorator nodes. Durations read the tree's clock (the world's sim clock in a run)."""

from __future__ import annotations

from typing import Any, ClassVar

from py_trees.ports import PortInformation

from bt_manip.bt.node import BtNode, DecoratorNode
from bt_manip.bt.ports import POSITIVE, Port
from bt_manip.bt.registry import registry
from bt_manip.bt.status import NodeStatus

IDLE = NodeStatus.IDLE
RUNNING = NodeStatus.RUNNING
SUCCESS = NodeStatus.SUCCESS
FAILURE = NodeStatus.FAILURE


@registry.register
class RateController(DecoratorNode):
    """Ticks its child at most ``hz`` times per second.

    When it starts (from IDLE) the child is ticked at once. After that the child is ticked
    again only once ``1/hz`` seconds have passed since the last time it succeeded, or while it
    is RUNNING. It returns the child's status when the child was ticked:

    - child SUCCESS: SUCCESS (the period restarts now);
    - child RUNNING: RUNNING;
    - child FAILURE: FAILURE.

    On a tick where the child is not due it returns RUNNING without ticking it.
    """

    INPUT_PORTS: ClassVar[dict[str, PortInformation]] = {
        "hz": Port(float, False, "Rate", 10.0, POSITIVE),
    }

    def __init__(self, name: str | None = None, child: BtNode | None = None,
                 **attributes: Any) -> None:
        super().__init__(name, child, **attributes)
        self.started = 0.0
        self.first_time = True

    def tick_node(self) -> NodeStatus:
        period = 1.0 / float(self.get_input("hz"))
        now = self.now()
        if self.bt_status is IDLE:
            self.started = now
            self.first_time = True
        self.bt_status = RUNNING
        self.status = RUNNING.to_py_trees()
        due = now - self.started >= period - 1e-9
        if self.first_time or self.child.bt_status is RUNNING or due:
            self.first_time = False
            status = self.child.execute_tick()
            if status is SUCCESS:
                self.started = now
            return status
        return RUNNING
