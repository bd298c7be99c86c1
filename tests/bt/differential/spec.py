"""What one differential case is: a tree document, a starting blackboard and a tick schedule.

A case is plain data (it travels as JSON to the oracle worker) and renders to BT.CPP v4 XML
that both engines load unchanged.
"""

from __future__ import annotations

import copy
from dataclasses import dataclass, field
from typing import Any
from xml.sax.saxutils import quoteattr

TICK = "tick"  # Tree::tickOnce()
TICK_EXACTLY_ONCE = "tick1"  # Tree::tickExactlyOnce()
HALT = "halt"  # Tree::haltTree()


@dataclass
class Node:
    """One XML element: its tag (node ID or ``SubTree``), attributes in order, children."""

    tag: str
    attrs: dict[str, str] = field(default_factory=dict)
    children: list[Node] = field(default_factory=list)

    def walk(self) -> list[Node]:
        """This node and every node under it, parents first."""
        out = [self]
        for child in self.children:
            out.extend(child.walk())
        return out

    def depth(self) -> int:
        return 1 + max((c.depth() for c in self.children), default=0)

    def render(self) -> str:
        attrs = "".join(f" {k}={quoteattr(v)}" for k, v in self.attrs.items())
        if not self.children:
            return f"<{self.tag}{attrs}/>"
        inner = "".join(c.render() for c in self.children)
        return f"<{self.tag}{attrs}>{inner}</{self.tag}>"

    def to_json(self) -> list[Any]:
        return [self.tag, dict(self.attrs), [c.to_json() for c in self.children]]

    @staticmethod
    def from_json(data: list[Any]) -> Node:
        tag, attrs, children = data
        return Node(tag, dict(attrs), [Node.from_json(c) for c in children])


@dataclass
class Case:
    """A tree (main tree plus subtree definitions), initial entries and what to do, in order.

    ``init`` lists ``(key, type, value)`` with type ``int``, ``bool``, ``str`` or ``float``: BT.CPP
    types an entry when it is created, so both engines start from the same typed entries.
    ``schedule`` is a list of ``tick`` (``tickOnce``), ``tick1`` (``tickExactlyOnce``) and
    ``halt`` (``haltTree``).
    """

    main: Node
    subtrees: dict[str, Node] = field(default_factory=dict)
    init: list[tuple[str, str, Any]] = field(default_factory=list)
    schedule: list[str] = field(default_factory=list)
    seed: int = 0

    def xml(self) -> str:
        parts = ['<root BTCPP_format="4" main_tree_to_execute="MainTree">',
                 f'<BehaviorTree ID="MainTree">{self.main.render()}</BehaviorTree>']
        for tree_id, body in self.subtrees.items():
            parts.append(f'<BehaviorTree ID="{tree_id}">{body.render()}</BehaviorTree>')
        parts.append("</root>")
        return "".join(parts)

    def pretty(self) -> str:
        """The XML with one element per line, indented (for failure messages and reports)."""
        lines = ['<root BTCPP_format="4" main_tree_to_execute="MainTree">']
        for tree_id, body in [("MainTree", self.main), *self.subtrees.items()]:
            lines.append(f'  <BehaviorTree ID="{tree_id}">')
            _pretty(body, 2, lines)
            lines.append("  </BehaviorTree>")
        lines.append("</root>")
        return "\n".join(lines)

    def init_text(self) -> str:
        return ", ".join(f"{k}={v!r} ({t})" for k, t, v in self.init) or "(empty)"

    def nodes(self) -> list[Node]:
        out = self.main.walk()
        for body in self.subtrees.values():
            out.extend(body.walk())
        return out

    def size(self) -> int:
        """A measure the shrinker makes smaller: nodes, attributes, schedule, entries."""
        return (sum(1 + len(n.attrs) for n in self.nodes()) * 4 + len(self.schedule)
                + len(self.init) + sum(len(v) for n in self.nodes() for v in n.attrs.values())
                // 8)

    def copy(self) -> Case:
        return copy.deepcopy(self)

    def to_json(self) -> dict[str, Any]:
        return {"xml": self.xml(), "init": [list(e) for e in self.init],
                "schedule": list(self.schedule)}


def _pretty(node: Node, level: int, lines: list[str]) -> None:
    pad = "  " * level
    attrs = "".join(f" {k}={quoteattr(v)}" for k, v in node.attrs.items())
    if not node.children:
        lines.append(f"{pad}<{node.tag}{attrs}/>")
        return
    lines.append(f"{pad}<{node.tag}{attrs}>")
    for child in node.children:
        _pretty(child, level + 1, lines)
    lines.append(f"{pad}</{node.tag}>")
