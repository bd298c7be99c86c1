"""``<TreeNodesModel>``: node declarations as Groot2 and BT.CPP write them.

Reading a model declares nodes that are not implemented here (for ``validate``: their IDs and
ports are known, so a tree using them is checked). Writing one exports every registered node
with typed, described ports, so Groot2 can import it::

    <root BTCPP_format="4">
      <TreeNodesModel>
        <Action ID="MoveBase">
          <input_port name="goal" type="Pose2D">where to go</input_port>
        </Action>
      </TreeNodesModel>
    </root>
"""

from __future__ import annotations

from dataclasses import dataclass, field
from xml.sax.saxutils import escape, quoteattr

from bt_manip.bt.node import BtNode
from bt_manip.bt.ports import direction_of, format_literal, type_from_name, type_name
from bt_manip.bt.xml_parse import Element
from bt_manip.errors import Problem

KINDS = ("Action", "Condition", "Control", "Decorator", "SubTree")
_PORT_TAGS = {"input_port": "input", "output_port": "output", "inout_port": "inout",
              "bidirectional_port": "inout"}  # the older name, still in Nav2's model file
_CHILDREN = {"Action": (0, 0), "Condition": (0, 0), "Control": (1, None), "Decorator": (1, 1),
             "SubTree": (0, 0)}


@dataclass(frozen=True)
class PortSpec:
    name: str
    direction: str  # "input", "output" or "inout"
    type_name: str = ""
    default: str | None = None
    description: str = ""


@dataclass
class NodeSpec:
    """What validation needs to know about one node ID."""

    node_id: str
    kind: str
    ports: dict[str, PortSpec] = field(default_factory=dict)
    description: str = ""
    min_children: int = 0
    max_children: int | None = 0
    cls: type[BtNode] | None = None
    line: int | None = None
    file: str | None = None


def spec_of(cls: type[BtNode]) -> NodeSpec:
    """The model of a registered node class."""
    ports: dict[str, PortSpec] = {}
    for is_output, table in ((False, cls.INPUT_PORTS), (True, cls.OUTPUT_PORTS)):
        for name, info in table.items():
            ports[name] = PortSpec(
                name=name,
                direction=direction_of(info, is_output),
                type_name=(cls.MODEL_TYPE_NAMES.get(name) or cls.PORT_TYPE_NAMES.get(name)
                           or type_name(info.data_type)),
                default=format_literal(info.default_value) if info.has_default else None,
                description=info.description,
            )
    return NodeSpec(cls.NODE_ID, cls.KIND, ports, (cls.__doc__ or "").strip().split("\n")[0],
                    cls.MIN_CHILDREN, cls.MAX_CHILDREN, cls)


def read_models(element: Element, file: str) -> tuple[dict[str, NodeSpec], list[Problem]]:
    """Node specs declared in a ``<TreeNodesModel>`` element."""
    specs: dict[str, NodeSpec] = {}
    problems: list[Problem] = []
    for node in element.children:
        if node.tag not in KINDS:
            if node.tag != "MetadataFields":
                problems.append(Problem(
                    file, node.line,
                    f"unknown element <{node.tag}> in TreeNodesModel; expected one of "
                    + ", ".join(f"<{k}>" for k in KINDS)))
            continue
        node_id = node.get("ID")
        if not node_id:
            problems.append(Problem(file, node.line, f"<{node.tag}> in TreeNodesModel needs an ID"))
            continue
        lo, hi = _CHILDREN[node.tag]
        spec = NodeSpec(node_id, node.tag, {}, node.get("description", "") or "", lo, hi,
                        None, node.line, file)
        for port in node.children:
            direction = _PORT_TAGS.get(port.tag)
            if direction is None:
                if port.tag not in ("description", "MetadataFields"):
                    problems.append(Problem(
                        file, port.line,
                        f"unknown element <{port.tag}> in model of {node_id}; expected "
                        "<input_port>, <output_port> or <inout_port>"))
                continue
            name = port.get("name")
            if not name:
                problems.append(Problem(file, port.line, f"port of {node_id} without a name"))
                continue
            spec.ports[name] = PortSpec(name, direction, port.get("type", "") or "",
                                        port.get("default"), port.text.strip())
        specs[node_id] = spec
    return specs, problems


def port_python_type(spec: PortSpec) -> object:
    return type_from_name(spec.type_name)


def write_models(classes: list[type[BtNode]]) -> str:
    """A ``<root BTCPP_format="4"><TreeNodesModel>`` document declaring ``classes``."""
    lines = ['<?xml version="1.0" encoding="UTF-8"?>', '<root BTCPP_format="4">',
             "  <TreeNodesModel>"]
    for cls in sorted(classes, key=lambda c: c.NODE_ID):
        spec = spec_of(cls)
        head = f"    <{spec.kind} ID={quoteattr(spec.node_id)}"
        if not spec.ports:
            lines.append(head + "/>")
            continue
        lines.append(head + ">")
        for port in spec.ports.values():
            attrs = f"name={quoteattr(port.name)}"
            if port.type_name:
                attrs += f" type={quoteattr(port.type_name)}"
            if port.default is not None:
                attrs += f" default={quoteattr(port.default)}"
            tag = f"{port.direction}_port"
            lines.append(f"      <{tag} {attrs}>{escape(port.description)}</{tag}>")
        lines.append(f"    </{spec.kind}>")
    lines += ["  </TreeNodesModel>", "</root>", ""]
    return "\n".join(lines)
