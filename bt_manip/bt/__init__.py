"""Behaviour-tree layer: BehaviorTree.CPP v4 XML, built-in nodes and semantics, on py_trees.

Public API::

    from bt_manip.bt import load_tree, validate_file, Tree, TreeContext, registry, to_xml
    from bt_manip.bt import ActionNode, ConditionNode   # base classes for robot behaviours
    from bt_manip.bt import from_py_trees               # a py_trees tree as a bt-manip Tree
"""

from bt_manip.bt import (  # noqa: F401  (register the built-ins)
    controls,
    decorators,
    entry_updates,
    leaves,
    loops,
)
from bt_manip.bt.blackboard import Blackboard
from bt_manip.bt.context import TreeContext
from bt_manip.bt.node import (
    ActionNode,
    BtNode,
    ConditionNode,
    ControlNode,
    DecoratorNode,
    PortError,
    SyncActionNode,
    TreeRuntimeError,
)
from bt_manip.bt.ports import InOutPortInformation
from bt_manip.bt.pytrees import from_py_trees, register_py_trees_behaviours  # installs itself
from bt_manip.bt.registry import registry
from bt_manip.bt.status import NodeStatus
from bt_manip.bt.subtree import SubTree
from bt_manip.bt.tree import NodeRecord, Tree
from bt_manip.bt.xml_loader import load_tree, load_tree_string, validate, validate_file
from bt_manip.bt.xml_writer import to_xml

register_py_trees_behaviours()  # py_trees' own leaves: <SuccessEveryN n="3"/> in XML

__all__ = [
    "ActionNode",
    "Blackboard",
    "BtNode",
    "ConditionNode",
    "ControlNode",
    "DecoratorNode",
    "InOutPortInformation",
    "NodeRecord",
    "NodeStatus",
    "PortError",
    "SubTree",
    "SyncActionNode",
    "Tree",
    "TreeContext",
    "TreeRuntimeError",
    "from_py_trees",
    "load_tree",
    "load_tree_string",
    "registry",
    "to_xml",
    "validate",
    "validate_file",
]
