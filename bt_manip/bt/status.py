"""BehaviorTree.CPP node statuses and every other form of them, derived in one place.

A node has two status facts: :class:`NodeStatus`, its status now (``BtNode.bt_status``), and
its last result (``BtNode.last_status``), what it last returned before its parent reset it to
IDLE. Everything else comes from those two here:

- py_trees ``Status``: BT.CPP knows five statuses, py_trees four. ``IDLE`` (never ticked, or
  reset) and ``SKIPPED`` (a pre-condition said "do not run me") both show as ``INVALID``.
- :data:`STATUS_CODES`: the integer codes of the pages and of Groot2's STATUS reply.
- :func:`shown`: what reports, consoles and pages display (the last result once finished).
- :func:`as_status`: a status given in any of these forms (name, py_trees, code) read back.
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
        return PY_TREES_OF[self]

    @staticmethod
    def from_py_trees(status: Status) -> NodeStatus:
        return STATUS_OF_PY_TREES[status]

    @staticmethod
    def parse(text: str) -> NodeStatus:
        """Parse ``SUCCESS``, ``FAILURE``, ``RUNNING``, ``SKIPPED`` or ``IDLE`` (any case)."""
        try:
            return NodeStatus[text.strip().upper()]
        except KeyError:
            raise ValueError(
                f"expected one of SUCCESS, FAILURE, RUNNING, SKIPPED, IDLE, got '{text}'"
            ) from None


PY_TREES_OF = {
    NodeStatus.IDLE: Status.INVALID,
    NodeStatus.RUNNING: Status.RUNNING,
    NodeStatus.SUCCESS: Status.SUCCESS,
    NodeStatus.FAILURE: Status.FAILURE,
    NodeStatus.SKIPPED: Status.INVALID,
}
"""The py_trees status of each status (IDLE and SKIPPED are both INVALID)."""
STATUS_OF_PY_TREES = {
    Status.INVALID: NodeStatus.IDLE,
    Status.RUNNING: NodeStatus.RUNNING,
    Status.SUCCESS: NodeStatus.SUCCESS,
    Status.FAILURE: NodeStatus.FAILURE,
}
"""The status of each py_trees status (INVALID is IDLE)."""
RESULT_OF_PY_TREES: dict[Status, NodeStatus] = {
    p: b for p, b in STATUS_OF_PY_TREES.items() if p is not Status.INVALID}
"""What a py_trees tick result means as a node's result (INVALID is no result)."""


STATUS_CODES: dict[NodeStatus, int] = {
    NodeStatus.IDLE: 0,
    NodeStatus.RUNNING: 1,
    NodeStatus.SUCCESS: 2,
    NodeStatus.FAILURE: 3,
    NodeStatus.SKIPPED: 4,
}
"""Integer code of each status, as the pages and Groot2's STATUS reply encode it."""
STATUS_OF_CODE: dict[int, NodeStatus] = {code: status for status, code in STATUS_CODES.items()}


def as_status(value: object) -> NodeStatus:
    """``value`` as a :class:`NodeStatus`: a NodeStatus, a py_trees ``Status``, an integer code
    or a name in either spelling (``INVALID`` is IDLE). Anything else (``""``, None) is IDLE."""
    if isinstance(value, NodeStatus):
        return value
    if isinstance(value, Status):
        return STATUS_OF_PY_TREES[value]
    if isinstance(value, int):
        return STATUS_OF_CODE.get(value, NodeStatus.IDLE)
    text = str(getattr(value, "name", value) or "").strip().upper()
    if text == "INVALID":
        return NodeStatus.IDLE
    try:
        return NodeStatus[text]
    except KeyError:
        return NodeStatus.IDLE


def status_code(value: object) -> int:
    """The integer code (:data:`STATUS_CODES`) of a status given in any form (:func:`as_status`)."""
    return STATUS_CODES[as_status(value)]


def shown(status: NodeStatus, last: NodeStatus) -> NodeStatus:
    """What a display shows for a node with ``status`` now that last returned ``last``: while
    it runs, its status; once finished and reset to IDLE, what it returned (SUCCESS, FAILURE
    or SKIPPED). A node halted while RUNNING returned nothing and shows IDLE."""
    if status is NodeStatus.IDLE and last is not NodeStatus.RUNNING:
        return last
    return status
