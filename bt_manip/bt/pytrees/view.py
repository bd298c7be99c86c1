"""BT.CPP built-ins of a converted py_trees tree, with py_trees' view of their children.

``from_py_trees`` uses BT.CPP's ``Sequence``, ``ReactiveSequence``, ``Fallback``,
``ReactiveFallback``, ``Inverter``, ``ForceSuccess`` and ``ForceFailure`` where they tick like
py_trees' nodes. They tick exactly as those built-ins (same calls, same results); what differs
is the ``status`` attribute of the nodes below them, the status py_trees tools and visitors
read. py_trees keeps a finished node's status until:

- its parent Sequence starts again (py_trees stops every child with INVALID), or its parent
  memory Selector resumes past it;
- a higher priority sibling takes over (a Selector whose chosen child changed, or a
  Sequence without memory whose child did not succeed: the children after it);
- an ancestor is halted (the whole subtree becomes INVALID).

These classes apply those rules to ``status`` only (``terminate(INVALID)`` of a child that had
finished is not called: the documented difference); ``bt_status`` keeps BT.CPP's meaning. They
share their built-in's ``NODE_ID`` and are not registered: ``to_xml`` writes the built-in, and
XML loads BT.CPP's node. :class:`PyTreesViewTree` does not clear finished nodes' statuses at
the next tick as a :class:`~bt_manip.bt.tree.Tree` does.
"""

from __future__ import annotations

from py_trees.behaviour import Behaviour
from py_trees.common import Status

from bt_manip.bt import controls, decorators
from bt_manip.bt.node import BtNode
from bt_manip.bt.status import NodeStatus
from bt_manip.bt.tree import Tree

INVALID = Status.INVALID


def invalidate(node: Behaviour) -> None:
    """py_trees' view of ``node`` stopped with INVALID: it and everything below it."""
    for below in node.iterate():
        below.status = INVALID


class _HaltedView(BtNode):
    """Halting the node makes its whole subtree INVALID in py_trees' view (mixed in before
    a built-in control or decorator)."""

    def halt(self) -> None:
        super().halt()
        for child in self.children:
            invalidate(child)


class _CompositeView(_HaltedView):
    """py_trees' bookkeeping of its children's statuses around a BT.CPP control's tick."""

    SELECTOR = False
    MEMORY = False
    _chosen = 0  # py_trees' ``current_child`` of a selector, as an index

    def tick_node(self) -> NodeStatus:
        node = self
        children = node.children
        if node.bt_status is not NodeStatus.RUNNING:  # py_trees (re)starts the composite
            if not self.SELECTOR:
                for child in children:
                    invalidate(child)
            self._chosen = 0
        elif self.SELECTOR and self.MEMORY:
            for child in children[:self._chosen]:
                invalidate(child)
        visited = node.context.visited
        mark = len(visited) if visited is not None else 0
        result = super().tick_node()  # the built-in's
        ticked = [n for n in (visited or [])[mark:] if n.parent is node]
        if ticked:
            index = children.index(ticked[-1])
            self._after_child(index, children[index].status)
        return result

    def _after_child(self, index: int, status: Status) -> None:
        children = self.children
        if self.SELECTOR:
            if status in (Status.RUNNING, Status.SUCCESS):
                if index != self._chosen:
                    for child in children[index + 1:]:
                        invalidate(child)
                self._chosen = index
            else:
                self._chosen = len(children) - 1
        elif not self.MEMORY and status != Status.SUCCESS:
            for child in children[index + 1:]:
                invalidate(child)


class Sequence(_CompositeView, controls.Sequence):
    __doc__ = controls.Sequence.__doc__
    MEMORY = True


class ReactiveSequence(_CompositeView, controls.ReactiveSequence):
    __doc__ = controls.ReactiveSequence.__doc__


class Fallback(_CompositeView, controls.Fallback):
    __doc__ = controls.Fallback.__doc__
    SELECTOR = True
    MEMORY = True


class ReactiveFallback(_CompositeView, controls.ReactiveFallback):
    __doc__ = controls.ReactiveFallback.__doc__
    SELECTOR = True


class Inverter(_HaltedView, decorators.Inverter):
    __doc__ = decorators.Inverter.__doc__


class ForceSuccess(_HaltedView, decorators.ForceSuccess):
    __doc__ = decorators.ForceSuccess.__doc__


class ForceFailure(_HaltedView, decorators.ForceFailure):
    __doc__ = decorators.ForceFailure.__doc__


class PyTreesViewTree(Tree):
    """A converted py_trees tree: finished nodes keep their status in py_trees' view until
    py_trees would clear it (see the module doc), not only for the tick they ran in."""

    def _new_visit(self) -> None:
        self.context.visited = []

