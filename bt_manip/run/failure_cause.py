"""The failure that ended a run: what the summary, the run report and bench name as its cause.

A failed run's root returned FAILURE because one of its children did (a Sequence's child), or
all of them did (every alternative of a Fallback), or because of its own logic (an Inverter
whose child succeeded, a Timeout). :func:`failure_cause` follows those failures down from the
root: a node's failure was caused by the children that returned FAILURE during its last run
(between its start and its own FAILURE). The nodes where that stops (no child failed in the
node's last run) are the failures that ended the run; the cause is the last of them that gave a
reason (its feedback), or the last of them when none did. So in a recovery pattern,
``Fallback(try, Sequence(back_off, AlwaysFailure))``, the cause is what failed in ``try``, not
the AlwaysFailure that passes the failure on.

Failures the tree dealt with (a node under ForceSuccess, a Fallback's alternative when a later
one succeeded, an attempt that a Retry repeated) are off that path and never named. Every node
stamps when it starts and when it returns FAILURE on one counter (``BtNode.started_order`` and
``failure_order``), so a child's failure in an earlier run of its parent is told from one in the
run that failed.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from bt_manip.bt.status import NodeStatus


@dataclass(frozen=True)
class FailureCause:
    """The node whose failure ended the run, and why."""

    path: str
    """Its path in the tree, names joined by '/' (as in the run report's ``nodes``)."""
    name: str
    node_id: str
    reason: str
    """Its own reason (feedback), or what it did when it gave none."""

    def text(self) -> str:
        return f"{self.path}: {self.reason}"


def failure_cause(tree: Any) -> FailureCause | None:
    """The cause of the root's last FAILURE in ``tree`` (a ``bt_manip.bt.Tree``), or None when
    the root did not fail."""
    paths = {id(node): path for path, _, node in tree.walk()}
    root = tree.root
    if root.last_status is not NodeStatus.FAILURE:
        return None
    ends: list[Any] = []
    stack = [root]
    while stack:
        node = stack.pop()
        failed = [
            child
            for child in node.bt_children()
            if child.last_status is NodeStatus.FAILURE
            and node.started_order < child.failure_order < node.failure_order
        ]
        if failed:
            stack.extend(failed)
        else:
            ends.append(node)
    with_reason = [node for node in ends if node.feedback_message]
    node = max(with_reason or ends, key=lambda n: n.failure_order)
    node_id = getattr(node, "tree_id", None) or node.NODE_ID
    reason = node.feedback_message or _own_logic(node, node_id)
    return FailureCause(paths.get(id(node), node.name), node.name, node_id, reason)


def _node_id(node: Any) -> str:
    return str(getattr(node, "tree_id", None) or node.NODE_ID)


def _own_logic(node: Any, node_id: str) -> str:
    """What a node that failed without a reason and without a failed child did: a decorator
    such as an Inverter failed because its child succeeded, and that child's own words (a
    condition's reading, say) tell why."""
    succeeded = [
        child
        for child in node.bt_children()
        if child.last_status is NodeStatus.SUCCESS and child.started_order >= node.started_order
    ]
    if not succeeded:
        return f"{node_id} returned FAILURE"
    child = max(succeeded, key=lambda c: c.started_order)
    text = f"{node_id} returned FAILURE because {_node_id(child)} '{child.name}' succeeded"
    return f"{text}: {child.feedback_message}" if child.feedback_message else text
