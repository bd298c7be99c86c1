"""Node UIDs, subtree instances and the tree XML, as BehaviorTree.CPP 4.x gives them to Groot2.

UIDs count from 1, depth first, a subtree's nodes numbered where its SubTree node stands (the
SubTree node first). Each SubTree node starts a subtree *instance* whose ``_fullpath`` is the
SubTree's name when the XML gave it one, else ``ID::uid``, prefixed by the enclosing instance's
path and ``/``; the main tree's path is empty. Instances are listed in the order they are met,
and the STATUS buffer lists the nodes instance by instance in that order.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from xml.sax.saxutils import escape, quoteattr

from bt_manip.bt.blackboard import Blackboard
from bt_manip.bt.models import spec_of
from bt_manip.bt.node import BtNode
from bt_manip.bt.registry import registry
from bt_manip.bt.subtree import SubTree
from bt_manip.bt.tree import Tree
from bt_manip.bt.walk import walk_nodes

INDENT = "    "
SUBTREE_AUTOREMAP = ("if true, every entry whose key does not start with '_' is shared "
                     "with the parent")


@dataclass
class Instance:
    """One subtree instance (the main tree is the first)."""

    tree_id: str
    path: str
    root: BtNode
    blackboard: Blackboard
    nodes: list[BtNode] = field(default_factory=list)

    @property
    def name(self) -> str:
        """How Groot2 asks for this instance's blackboard: its path, the main tree by its ID."""
        return self.path or self.tree_id


@dataclass
class TreeLayout:
    """UIDs and subtree instances of one tree."""

    instances: list[Instance]
    uid_of: dict[int, int]
    """``id(node)`` -> UID."""
    nodes_by_uid: dict[int, BtNode]

    def uid(self, node: BtNode) -> int:
        return self.uid_of[id(node)]

    def status_order(self) -> list[int]:
        """UIDs in the order of the STATUS buffer (instance by instance)."""
        return [self.uid(node) for inst in self.instances for node in inst.nodes]

    def instance(self, name: str) -> Instance | None:
        for inst in self.instances:
            if inst.name == name:
                return inst
        return None


def layout_of(tree: Tree) -> TreeLayout:
    """Number the nodes of ``tree`` and list its subtree instances, as BT.CPP does."""
    main = Instance(tree.tree_id, "", tree.root, tree.blackboard)
    layout = TreeLayout([main], {}, {})

    instance_of: list[Instance] = []  # by walk index: the instance the node belongs to
    for walked in walk_nodes(tree.root):
        node = walked.node
        uid = walked.index + 1
        layout.uid_of[id(node)] = uid
        layout.nodes_by_uid[uid] = node
        inst = main if walked.parent < 0 else instance_of[walked.parent]
        parent = layout.nodes_by_uid.get(walked.parent + 1) if walked.parent >= 0 else None
        if isinstance(parent, SubTree):
            # the root of a subtree: a new instance, named by its SubTree node
            own = parent.name
            if own == parent.tree_id:
                own = f"{parent.tree_id}::{walked.parent + 1}"
            path = f"{inst.path}/{own}" if inst.path else own
            inst = Instance(parent.tree_id, path, node, node.blackboard)
            layout.instances.append(inst)
        inst.nodes.append(node)
        instance_of.append(inst)
    return layout


def _attrs(pairs: list[tuple[str, str]]) -> str:
    return "".join(f" {key}={quoteattr(value)}" for key, value in pairs)


def _node_xml(node: BtNode, layout: TreeLayout, depth: int, out: list[str]) -> None:
    pad = INDENT * depth
    uid = str(layout.uid(node))
    if isinstance(node, SubTree):
        inst = next(i for i in layout.instances if i.root is node.child)
        pairs = [("ID", node.tree_id), ("_fullpath", inst.path), ("_uid", uid)]
        pairs += [(k, v) for k, v in node.attribute_texts.items() if k != "_autoremap"]
        out.append(f"{pad}<SubTree{_attrs(pairs)}/>")
        return
    pairs = [("name", node.name), ("_uid", uid), *node.attribute_texts.items()]
    children = node.bt_children()
    if not children:
        out.append(f"{pad}<{node.NODE_ID}{_attrs(pairs)}/>")
        return
    out.append(f"{pad}<{node.NODE_ID}{_attrs(pairs)}>")
    for child in children:
        _node_xml(child, layout, depth + 1, out)
    out.append(f"{pad}</{node.NODE_ID}>")


def models_xml(classes: list[type[BtNode]], depth: int = 1) -> list[str]:
    """``<TreeNodesModel>`` lines declaring ``classes`` and SubTree (whose ``_autoremap`` port
    BT.CPP declares), sorted by ID; ports with type, default and description."""
    pad = INDENT * depth
    entries: dict[str, list[str]] = {
        "SubTree": [f'{pad}{INDENT}<SubTree ID="SubTree">',
                    f'{pad}{INDENT * 2}<input_port name="_autoremap" type="bool" '
                    f'default="false">{escape(SUBTREE_AUTOREMAP)}</input_port>',
                    f"{pad}{INDENT}</SubTree>"]}
    for cls in classes:
        if cls.NODE_ID == "SubTree":
            continue
        spec = spec_of(cls)
        head = f"{pad}{INDENT}<{spec.kind} ID={quoteattr(spec.node_id)}"
        if not spec.ports:
            entries[spec.node_id] = [head + "/>"]
            continue
        lines = [head + ">"]
        for port in spec.ports.values():
            pairs = [("name", port.name)]
            if port.type_name:
                pairs.append(("type", port.type_name))
            if port.default is not None:
                pairs.append(("default", port.default))
            tag = f"{port.direction}_port"
            text = escape(port.description)
            line = f"{pad}{INDENT * 2}<{tag}{_attrs(pairs)}"
            lines.append(f"{line}>{text}</{tag}>" if text else f"{line}/>")
        lines.append(f"{pad}{INDENT}</{spec.kind}>")
        entries[spec.node_id] = lines
    out = [f"{pad}<TreeNodesModel>"]
    for node_id in sorted(entries):
        out += entries[node_id]
    out.append(f"{pad}</TreeNodesModel>")
    return out


def tree_xml(layout: TreeLayout, classes: list[type[BtNode]]) -> str:
    """The XML Groot2 gets for FULLTREE (and a .btlog holds): one ``<BehaviorTree>`` per
    instance with ``_fullpath`` and every node's ``_uid``, then the TreeNodesModel of
    ``classes`` (every registered node, built-ins included)."""
    out = ['<root BTCPP_format="4">']
    for inst in layout.instances:
        head = _attrs([("ID", inst.tree_id), ("_fullpath", inst.path)])
        out.append(f"{INDENT}<BehaviorTree{head}>")
        _node_xml(inst.root, layout, 2, out)
        out.append(f"{INDENT}</BehaviorTree>")
    out += models_xml(classes)
    out.append("</root>")
    return "\n".join(out) + "\n"


def registered_classes() -> list[type[BtNode]]:
    """Every node class of the registry (robot behaviours are there once imported)."""
    return registry.classes()
