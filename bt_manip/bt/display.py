"""Text and Graphviz views of a tree.

:func:`render_status` is the compact live view (one line per node, a status marker, the failure
reason); :func:`render_tree` is the static outline that ``bt-manip show`` prints;
:func:`render_dot` is the Graphviz source for ``show --dot``.
"""

from __future__ import annotations

from bt_manip.bt.node import BtNode
from bt_manip.bt.status import shown
from bt_manip.bt.subtree import SubTree
from bt_manip.bt.tree import Tree
from bt_manip.bt.walk import walk_nodes

MARKERS = {"IDLE": " ", "RUNNING": "*", "SUCCESS": "+", "FAILURE": "x", "SKIPPED": "-"}
_SHAPES = {"Action": "box", "Condition": "ellipse", "Control": "box3d",
           "Decorator": "hexagon", "SubTree": "folder"}


def _label(node: BtNode) -> str:
    if isinstance(node, SubTree):
        head = f"SubTree {node.tree_id}"
        return head if node.name == node.tree_id else f"{head} '{node.name}'"
    return node.NODE_ID if node.name == node.NODE_ID else f"{node.NODE_ID} '{node.name}'"


def _ports(node: BtNode) -> str:
    texts = [f"{k}={v}" for k, v in node.attribute_texts.items()]
    return f" ({', '.join(texts)})" if texts else ""


def render_status(tree: Tree) -> str:
    """One line per node: ``[marker] label``; markers: * running, + success, x failure,
    - skipped, blank not run yet. A node that finished shows what it returned last (in
    BehaviorTree.CPP it is IDLE again). Its feedback message (failure reason) follows ``--``."""
    lines = []
    for _, depth, node in tree.walk():
        marker = MARKERS[shown(node.bt_status, node.last_status).value]
        reason = f" -- {node.feedback_message}" if node.feedback_message else ""
        lines.append(f"{'  ' * depth}[{marker}] {_label(node)}{reason}")
    return "\n".join(lines)


def render_tree(tree: Tree) -> str:
    """Static outline of the tree with each node's attributes."""
    lines = [f"BehaviorTree {tree.tree_id}"]
    for _, depth, node in tree.walk():
        lines.append(f"{'  ' * (depth + 1)}{_label(node)}{_ports(node)}")
    return "\n".join(lines)


def _dot_escape(text: str) -> str:
    return text.replace("\\", "\\\\").replace('"', '\\"')


def render_dot(tree: Tree) -> str:
    """Graphviz (dot) source of the tree."""
    lines = [f'digraph "{_dot_escape(tree.tree_id)}" {{', "  rankdir=TB;",
             '  node [fontname="Helvetica", fontsize=10];']
    walked_nodes = list(walk_nodes(tree.root))
    for walked in walked_nodes:
        index, node = walked.index, walked.node
        kind = "SubTree" if isinstance(node, SubTree) else node.KIND
        label = _dot_escape(_label(node))
        if node.attribute_texts:
            label += "\\n" + "\\n".join(
                _dot_escape(f"{k}={v}") for k, v in node.attribute_texts.items())
        lines.append(f'  n{index} [label="{label}", '
                     f"shape={_SHAPES.get(kind, 'box')}];")
    for walked in walked_nodes:
        if walked.parent >= 0:
            lines.append(f"  n{walked.parent} -> n{walked.index};")
    lines.append("}")
    return "\n".join(lines) + "\n"
