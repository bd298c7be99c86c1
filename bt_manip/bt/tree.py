"""A loaded (or Python-built) tree: its root, blackboard, context, and how to tick it."""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass
from typing import Any

from py_trees.common import Status

from bt_manip.bt.blackboard import Blackboard, EntryTypeError
from bt_manip.bt.context import TreeContext
from bt_manip.bt.node import BtNode
from bt_manip.bt.ports import Ref
from bt_manip.bt.status import NodeStatus
from bt_manip.bt.subtree import SubTree
from bt_manip.bt.walk import walk_nodes
from bt_manip.errors import InputError, Problem

INVALID = Status.INVALID
MAX_WAKE_UPS = 1000
"""Re-ticks one ``Tree.tick()`` makes for wake-up signals before it returns to its caller."""


@dataclass
class NodeRecord:
    """One node of a tree as the run report and the console show it."""

    path: str
    name: str
    node_id: str
    status: str
    reason: str
    depth: int
    last_status: str = "IDLE"

    @property
    def node(self) -> str:
        """The node ID (same as ``node_id``; the runner's report calls it ``node``)."""
        return self.node_id


class Tree:
    """A tree ready to tick.

    ``tick()`` is BT.CPP's ``Tree::tickOnce()``: it ticks the root, then ticks it again as long
    as the root is RUNNING and a node asked for a wake-up (see :meth:`BtNode.emit_wake_up`);
    ``tick_exactly_once()`` ticks the root once whatever is pending. Both return the root's
    :class:`NodeStatus` (also kept in :attr:`bt_status`); a root that finished (SUCCESS or
    FAILURE) is reset to IDLE afterwards, as in BT.CPP, so the next tick starts it again.
    ``halt()`` is ``haltTree()``: every RUNNING node's ``terminate(INVALID)`` runs once, and
    every node's ``_onHalted`` script runs.

    A wake-up loop cannot hold ``tick()`` for ever: before each re-tick the timers whose time
    has come fire (a Timeout over ``RetryUntilSuccessful num_attempts="-1"`` ends on the wall
    clock as in BT.CPP, whose timers run on their own thread), and after
    :attr:`max_wake_ups` re-ticks ``tick()`` returns RUNNING with the signal still pending, so
    that its caller can check its budgets and move the sim clock (which only moves between
    ticks); the next ``tick()`` goes on where the loop stopped.
    """

    max_wake_ups: int = MAX_WAKE_UPS
    """Re-ticks for wake-up signals within one ``tick()`` (see :data:`MAX_WAKE_UPS`)."""

    warnings: list[Problem]
    """The loader's warnings, set on trees loaded from a file (no attribute otherwise)."""

    def __init__(
        self,
        root: BtNode,
        context: TreeContext | None = None,
        blackboard: Blackboard | dict[str, Any] | None = None,
        tree_id: str = "MainTree",
        source: str | None = None,
    ) -> None:
        self.root = root
        self.context = context or TreeContext()
        self.blackboard = (
            blackboard if isinstance(blackboard, Blackboard) else Blackboard.from_dict(blackboard)
        )
        self.tree_id = tree_id
        self.source = source
        self.bt_status = NodeStatus.IDLE
        self.tick_count = 0
        self.context.tree = self
        self.context.visited = []
        self._wire(root, self.blackboard)

    def _wire(self, node: BtNode, bb: Blackboard) -> None:
        node.blackboard = bb
        node.context = self.context
        if isinstance(node, SubTree):
            self._wire(node.child, node.make_blackboard(bb))
            return
        for port, binding in node.bindings.items():
            if isinstance(binding, Ref):
                info = node.port_info(port)
                if info is not None:
                    try:
                        bb.declare(binding.key, info.data_type, node.PORT_TYPE_NAMES.get(port))
                    except EntryTypeError as e:
                        raise InputError.single(
                            node.xml_file or self.source or "<tree>", node.xml_line,
                            f"{node.NODE_ID} port '{port}': {e}") from None
        for child in node.bt_children():
            self._wire(child, bb)

    def tick(self) -> NodeStatus:
        """Tick the root, again while it is RUNNING and a wake-up is pending (``tickOnce``)."""
        self.tick_count += 1
        root = self.root
        context = self.context
        self._new_visit()
        if context.timers:
            context.fire_timers()
        status = root.execute_tick()
        wake_ups = self.max_wake_ups
        while status is NodeStatus.RUNNING and context.wake_up and wake_ups > 0:
            wake_ups -= 1
            context.wake_up = False
            if context.timers:  # the clock may have moved (the wall clock does)
                context.fire_timers()
            status = root.execute_tick()
        return self._finish(status)

    def tick_exactly_once(self) -> NodeStatus:
        """Tick the root once, even if a wake-up is pending (``tickExactlyOnce``)."""
        self.tick_count += 1
        self._new_visit()
        if self.context.timers:
            self.context.fire_timers()
        return self._finish(self.root.execute_tick())

    def _new_visit(self) -> None:
        """Start a tick's list of visited nodes; nodes of the previous tick that finished and
        were reset stop showing their status to py_trees tools (see ``BtNode.reset_status``)."""
        visited = self.context.visited
        if visited:
            idle = NodeStatus.IDLE
            for node in visited:
                if node.bt_status is idle:
                    node.status = INVALID
        self.context.visited = []

    def visited_nodes(self) -> list[BtNode]:
        """Every node that ran in the last tick once, in the order it last returned (children
        before their parent, the root last)."""
        seen: dict[int, BtNode] = {}
        for node in self.context.visited or []:
            seen.pop(id(node), None)
            seen[id(node)] = node
        return list(seen.values())

    def _finish(self, status: NodeStatus) -> NodeStatus:
        if status is NodeStatus.SUCCESS or status is NodeStatus.FAILURE:
            self.root.reset_status()
        self.bt_status = status
        return status

    def tick_while_running(self, max_ticks: int = 1_000_000) -> NodeStatus:
        """Tick until the root is not RUNNING (or ``max_ticks``); for tests and scripts."""
        status = NodeStatus.IDLE
        for _ in range(max_ticks):
            self.tick()
            status = self.bt_status
            if status is not NodeStatus.RUNNING:
                break
        return status

    def halt(self) -> None:
        """Halt the whole tree and make it IDLE (BT.CPP's ``Tree::haltTree()``).

        The root is halted (each RUNNING node's ``terminate(INVALID)`` runs once, then its
        ``_onHalted``), then, as BT.CPP does to be sure, every node is halted again, parents
        before children: a node's ``_onHalted`` script runs even if it was IDLE (twice for the
        root and for the nodes that were RUNNING), while ``terminate`` never runs twice.
        """
        root = self.root
        root.halt_node()
        for node in self.nodes():
            node.halt_node()
        root.reset_status()
        for node in self.nodes():
            node.status = INVALID
        self.bt_status = NodeStatus.IDLE

    def walk(self) -> Iterator[tuple[str, int, BtNode]]:
        """Every node with its path and depth, depth first, parents before children (see
        :func:`bt_manip.bt.walk.walk_nodes`)."""
        for walked in walk_nodes(self.root):
            yield walked.path, walked.depth, walked.node

    def node_records(self) -> list[NodeRecord]:
        """Every node as the run report and the console show it, in walk order."""
        return [
            NodeRecord(
                path=walked.path,
                name=walked.name,
                node_id=walked.node_id,
                status=walked.node.bt_status.value,
                reason=walked.node.feedback_message or "",
                depth=walked.depth,
                last_status=walked.node.last_status.value,
            )
            for walked in walk_nodes(self.root)
        ]

    def nodes(self) -> list[BtNode]:
        return [node for _, _, node in self.walk()]
