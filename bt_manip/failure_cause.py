"""The failure that ended a run: what the summary, the run report and bench name as its cause.

A failed run's root returned FAILURE because one of its children did (a Sequence's child), or
all of them did (a Fallback's last alternative), or because of its own logic (an Inverter whose
child succeeded, a Timeout). :func:`failure_cause` walks from the root down that path: at each
node it goes to the child whose FAILURE came last before the node's own, among children whose
last result was FAILURE; it stops at a node none of whose children failed that way. Failures
the tree dealt with (a Reverse under ForceSuccess, a Fallback's first alternative that a later
one replaced, an attempt that a Retry repeated) are off that path and never named.

Every node stamps each FAILURE it returns with a rank (``BtNode.failure_order``), so a child's
failure from an earlier attempt is told from the one in the attempt that failed.
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
    node = tree.root
    if node.last_status is not NodeStatus.FAILURE:
        return None
    while True:
        failed = [
            child
            for child in node.bt_children()
            if child.last_status is NodeStatus.FAILURE
            and 0 < child.failure_order < node.failure_order
        ]
        if not failed:
            break
        node = max(failed, key=lambda child: child.failure_order)
    node_id = getattr(node, "tree_id", None) or node.NODE_ID
    reason = node.feedback_message or f"{node_id} returned FAILURE"
    return FailureCause(paths.get(id(node), node.name), node.name, node_id, reason)
