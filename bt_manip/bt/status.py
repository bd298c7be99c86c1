"""BehaviorTree.CPP node statuses and their mapping to py_trees statuses.

BT.CPP knows five statuses; py_trees knows four. ``IDLE`` (never ticked, or reset) and
``SKIPPED`` (a pre-condition said "do not run me") both show as ``INVALID`` in py_trees.
"""

from __future__ import annotations

import enum

from py_trees.common import Status


class NodeStatus(enum.Enum):
    """Status of a node as BehaviorTree.CPP defines it."""

    IDLE = "IDLE"
    RUNNING = "RUNNING"
    SUCCESS = "SUCCESS"
    FAILURE = "FAILURE"
    SKIPPED = "SKIPPED"

    @property
    def completed(self) -> bool:
        """True for SUCCESS and FAILURE."""
        return self is NodeStatus.SUCCESS or self is NodeStatus.FAILURE

    def to_py_trees(self) -> Status:
        return _TO_PY_TREES[self]

    @staticmethod
    def from_py_trees(status: Status) -> NodeStatus:
        return _FROM_PY_TREES[status]

    @staticmethod
    def parse(text: str) -> NodeStatus:
        """Parse ``SUCCESS``, ``FAILURE``, ``RUNNING``, ``SKIPPED`` or ``IDLE`` (any case)."""
        try:
            return NodeStatus[text.strip().upper()]
        except KeyError:
            raise ValueError(
                f"expected one of SUCCESS, FAILURE, RUNNING, SKIPPED, IDLE, got '{text}'"
            ) from None


_TO_PY_TREES = {
    NodeStatus.IDLE: Status.INVALID,
    NodeStatus.RUNNING: Status.RUNNING,
    NodeStatus.SUCCESS: Status.SUCCESS,
    NodeStatus.FAILURE: Status.FAILURE,
    NodeStatus.SKIPPED: Status.INVALID,
}
_FROM_PY_TREES = {
    Status.INVALID: NodeStatus.IDLE,
    Status.RUNNING: NodeStatus.RUNNING,
    Status.SUCCESS: NodeStatus.SUCCESS,
    Status.FAILURE: NodeStatus.FAILURE,
}
