"""BehaviorTree.CPP's nodes that watch a blackboard entry for new writes.

Every write to an entry bumps its update counter (:meth:`Blackboard.sequence_id`). Each node
remembers the counter it saw last, so "updated" means "written since this node last looked".

- ``WasEntryUpdated`` (action): SUCCESS if the entry was written since the last tick, FAILURE
  otherwise (or when the entry does not exist).
- ``SkipUnlessUpdated`` (decorator): ticks its child only if the entry was written; SKIPPED
  otherwise.
- ``WaitValueUpdate`` (decorator): ticks its child only if the entry was written; RUNNING
  otherwise.

A child that returned RUNNING is ticked again at the next tick without looking at the entry.
"""

from __future__ import annotations

from typing import Any

from py_trees.common import Status
from py_trees.ports import PortInformation

from bt_manip.bt.node import BtNode, DecoratorNode, SyncActionNode
from bt_manip.bt.ports import Ref
from bt_manip.bt.registry import registry
from bt_manip.bt.status import NodeStatus

ENTRY_PORT: dict[str, PortInformation] = {
    "entry": PortInformation(object, description="Entry to check")}


ENTRY_TYPE = {"entry": "BT::Any"}


class _EntryWatch:
    """The last update counter a node saw of its entry."""

    def __init__(self) -> None:
        self.seen = 0

    def updated(self, node: BtNode) -> bool:
        """Whether the entry was written since the last call (False if it does not exist)."""
        binding = node.bindings["entry"]
        key = binding.key if isinstance(binding, Ref) else str(binding.value)
        current = node.blackboard.sequence_id(key)
        if current is None:
            return False
        previous, self.seen = self.seen, current
        return previous != current


@registry.register(builtin=True)
class WasEntryUpdated(SyncActionNode):
    """SUCCESS if the entry ``entry`` was written since this node's last tick, else FAILURE."""

    INPUT_PORTS: dict[str, PortInformation] = (
        ENTRY_PORT)
    PORT_TYPE_NAMES = ENTRY_TYPE

    def __init__(self, name: str | None = None, **attributes: Any) -> None:
        super().__init__(name, **attributes)
        self._watch = _EntryWatch()

    def update(self) -> Status:
        return Status.SUCCESS if self._watch.updated(self) else Status.FAILURE


class _EntryUpdatedDecorator(DecoratorNode):
    IF_NOT_UPDATED = NodeStatus.SKIPPED
    INPUT_PORTS: dict[str, PortInformation] = (
        ENTRY_PORT)
    PORT_TYPE_NAMES = ENTRY_TYPE

    def __init__(self, name: str | None = None, child: BtNode | None = None,
                 **attributes: Any) -> None:
        super().__init__(name, child, **attributes)
        self._watch = _EntryWatch()
        self._child_running = False

    def tick_node(self) -> NodeStatus:
        if not self._child_running and not self._watch.updated(self):
            return self.IF_NOT_UPDATED
        status = self.child.execute_tick()
        self._child_running = status is NodeStatus.RUNNING
        return status

    def halt(self) -> None:
        self._child_running = False
        super().halt()


@registry.register(builtin=True)
class SkipUnlessUpdated(_EntryUpdatedDecorator):
    """Ticks the child only if ``entry`` was written since the last look; SKIPPED otherwise.

    A RUNNING child is ticked again at the next tick without looking at the entry; the child's
    status is returned. Halting it halts the child.
    """


@registry.register(builtin=True)
class WaitValueUpdate(_EntryUpdatedDecorator):
    """Ticks the child only if ``entry`` was written since the last look; RUNNING otherwise.

    A RUNNING child is ticked again at the next tick without looking at the entry; the child's
    status is returned. Halting it halts the child.
    """

    IF_NOT_UPDATED = NodeStatus.RUNNING
