"""Converting a py_trees tree into a bt-manip :class:`~bt_manip.bt.tree.Tree`.

``from_py_trees(root)`` gives a tree that ticks with the same statuses, tick by tick, as
py_trees ticking ``root``. A py_trees composite or decorator becomes a BehaviorTree.CPP
built-in only where the two agree on every tick:

==========================================  ============================================
py_trees                                    bt-manip
==========================================  ============================================
``Sequence(memory=True)``                   ``Sequence`` (resumes from the RUNNING child,
                                            restarts after a failure)
``Sequence(memory=False)``                  ``ReactiveSequence``
``Selector(memory=True)``                   ``Fallback``
``Selector(memory=False)``                  ``ReactiveFallback``
``Inverter``                                ``Inverter``
``FailureIsSuccess`` / ``SuccessIsFailure``   ``ForceSuccess`` / ``ForceFailure``
==========================================  ============================================

Everything else becomes a node with py_trees' semantics from
:mod:`bt_manip.bt.pytrees.composites`: ``Parallel`` (py_trees ticks every child before
deciding, BT.CPP's Parallel stops at its thresholds and has no SuccessOnSelected), ``Repeat``
and ``Retry`` (py_trees returns RUNNING between cycles), ``Timeout`` (checked after ticking
the child, on the tree's clock), ``OneShot``, ``Count``, ``Condition``, ``EternalGuard``,
``ForEach``, ``StatusToBlackboard``, ``PassThrough``, ``RunningIs*``, ``*IsRunning``, and
composites without children (BT.CPP controls need one). A composite or decorator of a class of
your own (or a subclass of py_trees' ones) becomes an instance of a subclass of that class
ticked by its own py_trees code, its state copied; such a node is written by ``to_xml`` but
cannot be loaded back from XML. With ``builtins=False`` every
composite and decorator gets its py_trees counterpart. One difference remains with built-ins:
py_trees stops a child that had finished when its parent starts again (its
``terminate(INVALID)`` runs once more); a BT.CPP parent resets it without calling it.

A ``Parallel`` whose SuccessOnSelected policy selects no child, or a behaviour that is not its
child, is converted all the same: as in py_trees, its check raises at every tick (here a
:class:`~bt_manip.bt.node.TreeRuntimeError` naming the node and those behaviours), and
``to_xml`` refuses the selection.

Leaves are wrapped (:mod:`bt_manip.bt.pytrees.leaf`), the very objects of the py_trees tree,
so references kept to them stay live; ``py_trees.timers.Timer`` becomes ``PyTreesTimer``, which
reads the tree's clock. Ports wired by ``setup_ports()`` before conversion (by the user's code or
py_trees' XML parser) keep their wiring, and the tree's blackboard starts with the entries that
``setup_ports()`` wrote (:mod:`bt_manip.bt.pytrees.wiring`). Nodes that already are bt-manip
nodes are kept.
"""

from __future__ import annotations

import copy
from typing import Any, cast

import py_trees
from py_trees.behaviour import Behaviour

from bt_manip.bt.attributes import UnwritableText
from bt_manip.bt.blackboard import Blackboard
from bt_manip.bt.context import TreeContext
from bt_manip.bt.node import BtNode
from bt_manip.bt.pytrees import composites as ptc
from bt_manip.bt.pytrees import view
from bt_manip.bt.pytrees.leaf import wrap
from bt_manip.bt.registry import registry
from bt_manip.bt.subtree import SubTree
from bt_manip.bt.tree import Tree
from bt_manip.bt.walk import walk_nodes

D = py_trees.decorators
_SIMPLE_DECORATORS: dict[type, type[BtNode]] = {
    D.PassThrough: ptc.PyTreesPassThrough,
    D.Inverter: ptc.PyTreesInverter,
    D.RunningIsFailure: ptc.PyTreesRunningIsFailure,
    D.RunningIsSuccess: ptc.PyTreesRunningIsSuccess,
    D.FailureIsSuccess: ptc.PyTreesFailureIsSuccess,
    D.FailureIsRunning: ptc.PyTreesFailureIsRunning,
    D.SuccessIsFailure: ptc.PyTreesSuccessIsFailure,
    D.SuccessIsRunning: ptc.PyTreesSuccessIsRunning,
    D.Count: ptc.PyTreesCount,
}
_BUILTIN_DECORATORS: dict[type, type[BtNode]] = {
    D.Inverter: view.Inverter,
    D.FailureIsSuccess: view.ForceSuccess,
    D.SuccessIsFailure: view.ForceFailure,
}


def from_py_trees(
    root: Behaviour,
    *,
    builtins: bool = True,
    context: TreeContext | None = None,
    blackboard: Blackboard | dict[str, Any] | None = None,
    tree_id: str = "MainTree",
) -> Tree:
    """A bt-manip tree ticking like the py_trees tree under ``root`` (see the module doc).

    Raises TypeError for a composite or decorator of a user's class that keeps a blackboard
    client in ``self.blackboard`` (bt-manip nodes use that name for their blackboard).
    """
    node = convert_node(root, builtins=builtins)
    tree = view.PyTreesViewTree(node, context=context, blackboard=blackboard, tree_id=tree_id)
    _register_leaves(node)
    _seed_setup_entries(tree)
    return tree


def convert_node(node: Behaviour, builtins: bool = True) -> BtNode:
    """The bt-manip node for one py_trees node and everything under it."""
    if isinstance(node, BtNode):
        if node.parent is not None and not isinstance(node.parent, BtNode):
            node.parent = None  # it moves from the py_trees parent to the converted one
        return node
    if isinstance(node, py_trees.composites.Composite):
        return _composite(node, builtins)
    if isinstance(node, py_trees.decorators.Decorator):
        return _decorator(node, builtins)
    return wrap(node)


def _children(node: Behaviour, builtins: bool) -> list[BtNode]:
    return [convert_node(child, builtins) for child in node.children]


def _composite(node: py_trees.composites.Composite, builtins: bool) -> BtNode:
    kind = type(node)
    name = node.name
    if kind is py_trees.composites.Parallel:  # the exact class, hence the casts below
        policy = cast(py_trees.composites.Parallel, node).policy
        originals = list(node.children)
        children = _children(node, builtins)
        attributes: dict[str, Any] = {"policy": type(policy).__name__,
                                      "synchronise": policy.synchronise}
        if not isinstance(policy, py_trees.common.ParallelPolicy.SuccessOnSelected):
            return ptc.PyTreesParallel(name, children, **attributes)
        selected = policy.children
        attributes["selected"] = [originals.index(c) for c in selected if c in originals]
        parallel = ptc.PyTreesParallel(name, children, **attributes)
        strangers = [c.name for c in selected if c not in originals]
        if strangers:  # py_trees' check raises at every tick, naming them; so does this one
            parallel.policy.children = [children[originals.index(c)] if c in originals else c
                                        for c in selected]
            parallel.attribute_texts["selected"] = UnwritableText(
                None, f"the SuccessOnSelected policy names {strangers}, which are not children "
                "of the parallel")
        return parallel
    if kind not in (py_trees.composites.Sequence, py_trees.composites.Selector):
        return _own_class(node, builtins)
    memory = bool(cast("py_trees.composites.Sequence | py_trees.composites.Selector", node).memory)
    children = _children(node, builtins)
    if builtins and children:
        if kind is py_trees.composites.Sequence:
            cls: type[BtNode] = view.Sequence if memory else view.ReactiveSequence
        else:
            cls = view.Fallback if memory else view.ReactiveFallback
        return cls(name, children=children)
    pt_cls = ptc.PyTreesSequence if kind is py_trees.composites.Sequence else ptc.PyTreesSelector
    return pt_cls(name, children, memory=memory)


def _decorator(node: py_trees.decorators.Decorator, builtins: bool) -> BtNode:
    kind = type(node)
    name = node.name
    child = convert_node(node.decorated, builtins)
    if builtins and kind in _BUILTIN_DECORATORS:
        return _BUILTIN_DECORATORS[kind](name, child=child)
    if kind in _SIMPLE_DECORATORS:
        return _SIMPLE_DECORATORS[kind](name, child)
    made: BtNode
    # each branch tests the exact class, which the cast names
    if kind is D.Repeat:
        made = ptc.PyTreesRepeat(name, child, num_success=cast(D.Repeat, node).num_success)
    elif kind is D.Retry:
        made = ptc.PyTreesRetry(name, child, num_failures=cast(D.Retry, node).num_failures)
    elif kind is D.Timeout:
        made = ptc.PyTreesTimeout(name, child, duration=float(cast(D.Timeout, node).duration))
    elif kind is D.OneShot:
        made = ptc.PyTreesOneShot(name, child, policy=cast(D.OneShot, node).policy.name)
    elif kind is D.Condition:
        made = ptc.PyTreesCondition(name, child,
                                    status=cast(D.Condition, node).succeed_status.name)
    elif kind is D.StatusToBlackboard:
        made = ptc.PyTreesStatusToBlackboard(
            name, child, variable_name=cast(D.StatusToBlackboard, node).variable_name)
    elif kind is D.ForEach:
        for_each = cast(D.ForEach, node)
        made = ptc.PyTreesForEach(name, child, source_key=for_each.source_key,
                                  target_key=for_each.target_key)
    elif kind is D.EternalGuard:
        original = cast(D.EternalGuard, node)
        guard = ptc.PyTreesEternalGuard(name, child, condition=original.condition)
        guard.condition = original.condition  # already bound to the original guard's client
        guard.blackboards.extend(node.blackboards)
        made = guard
    else:
        return _own_class(node, builtins)
    return made


_OWN_CLASSES: dict[type, type[BtNode]] = {}


def _own_class(node: Behaviour, builtins: bool) -> BtNode:
    """A user's composite or decorator class (or a subclass of py_trees' own): the node
    becomes an instance of a subclass of that class, with the object's state copied, ticked
    by the class's own py_trees code. It can be saved as XML but not loaded back."""
    user_class = type(node)
    if "blackboard" in vars(node):
        raise TypeError(f"cannot convert '{node.name}' of class {user_class.__qualname__}: it "
                        "keeps a blackboard client in self.blackboard, the name bt-manip nodes "
                        "use for their blackboard; rename the attribute")
    composite = isinstance(node, py_trees.composites.Composite)
    made_class = _OWN_CLASSES.get(user_class)
    if made_class is None:
        base = ptc._PyTreesComposite if composite else ptc._PyTreesDecorator
        made_class = type(user_class.__name__, (base, user_class), {
            "PY": user_class, "NODE_ID": user_class.__name__, "PYTHON_ONLY": True,
            "__module__": user_class.__module__, "__qualname__": user_class.__qualname__,
            "__doc__": user_class.__doc__ or f"py_trees node {user_class.__qualname__}"})
        _OWN_CLASSES[user_class] = made_class
    made: Any = made_class.__new__(made_class)
    vars(made).update(vars(node))  # the object's state, as it is
    kids = [convert_node(child, builtins) for child in node.children]
    made.children = []
    for kid in kids:
        kid.parent = made
        made.children.append(kid)
    if composite:
        made.current_child = None
        policy = getattr(node, "policy", None)
        if policy is not None and hasattr(policy, "children"):
            made.policy = copy.copy(policy)
            made.policy.children = [kids[node.children.index(c)] for c in policy.children]
    else:
        made.decorated = kids[0]
    made.parent = None
    made.status = py_trees.common.Status.INVALID
    made._init_node({})
    return cast(BtNode, made)  # an instance of made_class, a BtNode subclass


def _seed_setup_entries(tree: Tree) -> None:
    """Write the entries py_trees' ``setup_ports()`` had written for the tree's behaviours
    (constants, outputs' defaults) where the tree's blackboard has none yet."""
    for walked in walk_nodes(tree.root):
        for key, value in getattr(walked.node, "setup_entries", {}).items():
            if not tree.blackboard.has_value(key):
                tree.blackboard.set(key, value)


def _register_leaves(root: BtNode) -> None:
    """Register the classes of the tree's leaves whose IDs are free, so the XML that
    ``to_xml`` writes loads back."""
    for walked in walk_nodes(root):
        node = walked.node
        if isinstance(node, SubTree) or getattr(node, "PYTHON_ONLY", False):
            continue
        if registry.get(node.NODE_ID) is None:
            registry.register(type(node))
