"""Saving a tree as BT.CPP v4 XML (for trees built in Python).

``to_xml(tree)`` writes the main tree and one ``<BehaviorTree>`` per distinct SubTree ID, then a
``<TreeNodesModel>`` declaring the nodes that are not BT.CPP built-ins; loading the result
with :func:`~bt_manip.bt.load_tree` gives an equivalent tree. Where it would not (an attribute
that XML cannot hold, such as a Python callable; a node whose ID is registered for another
class), ``to_xml`` raises ValueError naming the node and the attribute.
"""

from __future__ import annotations

from xml.sax.saxutils import quoteattr

from bt_manip.bt.attributes import UnwritableText
from bt_manip.bt.models import write_models
from bt_manip.bt.node import BtNode
from bt_manip.bt.registry import registry
from bt_manip.bt.subtree import SubTree
from bt_manip.bt.tree import Tree
from bt_manip.bt.walk import walk_nodes

EXPLICIT_TAGS = ("Action", "Condition", "Control", "Decorator")
"""Tags that name a node's kind: a node with such an ID is written ``<Action ID="Action"/>``."""


def _node_lines(node: BtNode, indent: int, subtrees: dict[str, BtNode], out: list[str]) -> None:
    pad = "  " * indent
    if isinstance(node, SubTree):
        attrs = f" ID={quoteattr(node.tree_id)}"
        if node.name != node.tree_id:
            attrs += f" name={quoteattr(node.name)}"
        subtrees.setdefault(node.tree_id, node.child)
        children: list[BtNode] = []
        tag = "SubTree"
    else:
        _check_writable(node)
        tag = node.NODE_ID
        attrs = f" name={quoteattr(node.name)}" if node.name != node.NODE_ID else ""
        if tag in EXPLICIT_TAGS or tag == "SubTree":  # <Action/> alone names no node
            attrs = f" ID={quoteattr(tag)}" + attrs
            tag = node.KIND
        children = node.bt_children()
    for key, text in node.attribute_texts.items():
        attrs += f" {key}={quoteattr(text)}"
    if not children:
        out.append(f"{pad}<{tag}{attrs}/>")
        return
    out.append(f"{pad}<{tag}{attrs}>")
    for child in children:
        _node_lines(child, indent + 1, subtrees, out)
    out.append(f"{pad}</{tag}>")


def _check_writable(node: BtNode) -> None:
    """Raise ValueError when the XML written for ``node`` would not load back as it is: an
    attribute XML cannot hold, or an ID registered for another class."""
    for key, text in node.attribute_texts.items():
        if isinstance(text, UnwritableText):
            raise ValueError(f"cannot write {node.describe()} as XML: its argument '{key}': "
                             f"{text.reason}")
    registered = registry.get(node.NODE_ID)
    if registered is None or (isinstance(node, registered) and \
            getattr(registered, "BEHAVIOUR", None) is getattr(type(node), "BEHAVIOUR", None)):
        return
    mine = getattr(type(node), "BEHAVIOUR", type(node))
    theirs = getattr(registered, "BEHAVIOUR", registered)
    raise ValueError(f"cannot write {node.describe()} as XML: its ID '{node.NODE_ID}' is "
                     f"registered for {theirs.__module__}.{theirs.__qualname__}, not for "
                     f"{mine.__module__}.{mine.__qualname__}; the file would load another "
                     "node (register the class under another ID)")


def root_to_xml(root: BtNode, tree_id: str = "MainTree") -> str:
    """XML document for a tree given by its root node."""
    out = ['<?xml version="1.0" encoding="UTF-8"?>',
           f'<root BTCPP_format="4" main_tree_to_execute={quoteattr(tree_id)}>']
    subtrees: dict[str, BtNode] = {}
    pending = [(tree_id, root)]
    written: set[str] = set()
    while pending:
        current_id, current_root = pending.pop(0)
        if current_id in written:
            continue
        written.add(current_id)
        out.append(f"  <BehaviorTree ID={quoteattr(current_id)}>")
        _node_lines(current_root, 2, subtrees, out)
        out.append("  </BehaviorTree>")
        for sub_id, sub_root in subtrees.items():
            if sub_id not in written:
                pending.append((sub_id, sub_root))
    out += _models(root)
    out += ["</root>", ""]
    return "\n".join(out)


def _models(root: BtNode) -> list[str]:
    """A ``<TreeNodesModel>`` declaring the tree's nodes that are not BT.CPP built-ins (so
    Groot2 knows their kind and ports)."""
    classes: dict[str, type[BtNode]] = {}
    for walked in walk_nodes(root):
        node = walked.node
        if not isinstance(node, SubTree) and not registry.is_builtin(node.NODE_ID):
            classes.setdefault(node.NODE_ID, type(node))
    if not classes:
        return []
    lines = write_models(list(classes.values())).split("\n")
    start = lines.index("  <TreeNodesModel>")
    end = lines.index("  </TreeNodesModel>")
    return lines[start:end + 1]


def to_xml(tree: Tree | BtNode) -> str:
    """BT.CPP v4 XML for a :class:`Tree` (or a root node)."""
    if isinstance(tree, Tree):
        return root_to_xml(tree.root, tree.tree_id)
    return root_to_xml(tree)
