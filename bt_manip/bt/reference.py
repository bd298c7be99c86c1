"""The node reference: what a registered node does and what its ports take, as text.

``bt-manip nodes NAME`` prints one node's :func:`reference_text`; ``bt-manip nodes --markdown``
writes :func:`reference_markdown`, the reference ``docs/nodes.md`` holds. Everything comes from
the node classes: the contract (what the node returns on each status, and what halting it does)
is the class docstring, and each port's type, default, accepted values and description are its
declaration. A port's unit is read from its description, where it is written in brackets
(``"how far to reverse (m)"``, ``"target pose x;y;z;yaw (m, rad; world)"``) or as words
(``"sim seconds allowed"``); a dimensionless number says so (``fraction``, ``coefficient``...).
"""

from __future__ import annotations

import inspect
import re
from dataclasses import dataclass

from py_trees.ports import PortInformation

from bt_manip.bt.attributes import closest
from bt_manip.bt.models import spec_of
from bt_manip.bt.node import BtNode
from bt_manip.bt.ports import Accepts, direction_of, format_literal
from bt_manip.bt.registry import NodeRegistry

UNITS = ("m", "mm", "m/s", "rad", "rad/s", "deg", "s", "sim s", "ms", "Hz", "kg", "V",
         "deg or rad", "fraction or V")
"""Units a port description may state in brackets."""
UNIT_WORDS = (("sim seconds", "s"), ("seconds", "s"), ("milliseconds", "ms"), ("kg", "kg"))
"""Units written as words at the start of a description, and the unit they stand for."""
DIMENSIONLESS = ("fraction", "coefficient", "factor", "quaternion", "weight", "percentage",
                 "ratio")
"""Words of a description that say a number has no unit."""
NO_UNIT = "none"
"""The unit shown for a dimensionless number."""

ORIGINS = ("BT.CPP built-in", "Nav2", "bt-manip", "py_trees", "plugin")
"""Where nodes come from, in the order the reference lists them."""
_ORIGIN_TEXT = {
    "BT.CPP built-in": "a BehaviorTree.CPP 4 built-in node, with its semantics",
    "Nav2": "a node of Nav2's nav2_behavior_tree, driving bt-manip's navigation",
    "bt-manip": "a bt-manip robot node (bt_manip.behaviours)",
    "py_trees": "a py_trees behaviour, wrapped as a leaf or a control node",
    "plugin": "a node registered by a module of your own (--import)",
}


@dataclass(frozen=True)
class PortReference:
    """One port as the reference shows it."""

    name: str
    direction: str
    type_name: str
    required: bool
    default: str | None
    unit: str
    accepts: str
    description: str


@dataclass(frozen=True)
class NodeReference:
    """One node as the reference shows it."""

    node_id: str
    kind: str
    origin: str
    module: str
    contract: str
    ports: list[PortReference]
    one_of: tuple[tuple[str, ...], ...]


def origin_of(cls: type[BtNode], reg: NodeRegistry) -> str:
    """Where the node comes from: one of :data:`ORIGINS`."""
    module = cls.__module__
    if reg.is_builtin(cls.NODE_ID):
        return "BT.CPP built-in"
    if module.startswith("bt_manip.nav2"):
        return "Nav2"
    if module.startswith("bt_manip.behaviours"):
        return "bt-manip"
    if module.startswith(("py_trees", "bt_manip.bt.pytrees")):
        return "py_trees"
    return "plugin"


def unit_of(description: str, is_number: bool = True) -> str:
    """The unit a port description states ('' when it states none; :data:`NO_UNIT` for a
    dimensionless number)."""
    for group in re.findall(r"\(([^()]*)\)", description):
        items = [item.strip() for item in re.split(r"[,;]", group)]
        found = [item for item in items if item in UNITS]
        if found:
            return ", ".join("s" if u == "sim s" else u for u in found)
    low = description.lower()
    for word, unit in UNIT_WORDS:
        if low.startswith(word):
            return unit
    if is_number and any(word in low for word in DIMENSIONLESS):
        return NO_UNIT
    return ""


def carries_number(type_name: str) -> bool:
    """Whether a port of this BT.CPP type name holds numbers with a possible unit."""
    return type_name in ("double", "float", "std::vector<double>")


def _accepts_text(info: PortInformation) -> str:
    rule: Accepts | None = getattr(info, "accepts", None)
    if rule is None:
        return ""
    if rule.choices:
        text = "one of " + ", ".join(format_literal(c) or '""' for c in rule.choices)
    else:
        text = rule.text()
    if text == "any value":
        return rule.what
    return f"{text}; {rule.what}" if rule.what else text


def node_reference(cls: type[BtNode], reg: NodeRegistry) -> NodeReference:
    """The reference of the registered class ``cls``."""
    spec = spec_of(cls)
    ports = []
    for is_output, table in ((False, cls.INPUT_PORTS), (True, cls.OUTPUT_PORTS)):
        for name, info in table.items():
            port = spec.ports[name]
            ports.append(PortReference(
                name=name,
                direction=direction_of(info, is_output),
                type_name=port.type_name,
                required=bool(info.required) and not info.has_default,
                default=format_literal(info.default_value) if info.has_default else None,
                unit=unit_of(info.description, carries_number(port.type_name)),
                accepts=_accepts_text(info),
                description=info.description,
            ))
    contract = inspect.cleandoc(cls.__doc__ or "") or "(no description)"
    return NodeReference(cls.NODE_ID, cls.KIND, origin_of(cls, reg), cls.__module__, contract,
                         ports, cls.REQUIRED_ONE_OF)


def find_node(name: str, reg: NodeRegistry) -> tuple[type[BtNode] | None, str]:
    """The class registered as ``name`` (exact, else the only case-insensitive match), or None
    and the suggestions to print (' (did you mean ...?)' or '')."""
    cls = reg.get(name)
    if cls is not None:
        return cls, ""
    same = [i for i in reg.ids() if i.lower() == name.lower()]
    if len(same) == 1:
        return reg.get(same[0]), ""
    return None, closest(name, set(reg.ids()))


def _one_of_text(groups: tuple[tuple[str, ...], ...]) -> list[str]:
    return ["exactly one of " + " | ".join(alt.replace("+", " and ") for alt in group)
            for group in groups]


def reference_text(ref: NodeReference) -> str:
    """The reference of one node as plain text (``bt-manip nodes NAME``)."""
    lines = [f"{ref.node_id}: {ref.kind}, {ref.origin} ({ref.module})", ""]
    lines += ["  " + line if line else "" for line in ref.contract.splitlines()]
    lines.append("")
    if not ref.ports:
        lines.append("Ports: none")
    else:
        lines.append("Ports:")
        for p in ref.ports:
            need = "required" if p.required else (
                f"default {p.default or chr(34) * 2}" if p.default is not None else "optional")
            facts = [p.direction, p.type_name or "any type", need]
            if p.unit:
                facts.append(f"unit {p.unit}")
            lines.append(f"  {p.name}: " + ", ".join(facts))
            if p.description:
                lines.append(f"      {p.description}")
            if p.accepts:
                lines.append(f"      accepts: {p.accepts}")
    for rule in _one_of_text(ref.one_of):
        lines.append(f"Give {rule} (checked when the tree is loaded).")
    return "\n".join(lines) + "\n"


def _cell(text: str) -> str:
    return text.replace("|", "\\|").replace("\n", " ") if text else ""


def reference_markdown(refs: list[NodeReference]) -> str:
    """The reference of ``refs`` as one Markdown document (``docs/nodes.md``)."""
    out = [
        "# Node reference",
        "",
        "Every node a tree can use, with what it does on each status (halted included) and its",
        "ports: direction, type, unit, default and accepted values. Generated by",
        "`bt-manip nodes --markdown > docs/nodes.md`; `bt-manip nodes NAME` prints one node's",
        "entry. Lengths are in metres and angles in radians unless a port says otherwise; a",
        "`default` of `\"\"` is the empty text or list.",
        "",
    ]
    for origin in ORIGINS:
        group = [r for r in refs if r.origin == origin]
        if not group:
            continue
        out += [f"## {origin} nodes", "", _ORIGIN_TEXT[origin].capitalize() + ":", ""]
        out.append(", ".join(f"[{r.node_id}](#{r.node_id.lower()})" for r in group))
        out.append("")
        for ref in group:
            out += [f"### {ref.node_id}", "", f"{ref.kind}, from `{ref.module}`.", ""]
            out += [ref.contract, ""]
            for rule in _one_of_text(ref.one_of):
                out += [f"Give {rule} (checked when the tree is loaded).", ""]
            if not ref.ports:
                out += ["No ports.", ""]
                continue
            out += ["| Port | Direction | Type | Unit | Default | Accepts | Description |",
                    "|---|---|---|---|---|---|---|"]
            for p in ref.ports:
                default = "(required)" if p.required else (
                    f"`{p.default}`" if p.default else ('`""`' if p.default == "" else ""))
                type_text = f"`{p.type_name}`" if p.type_name else ""
                out.append(f"| `{p.name}` | {p.direction} | {_cell(type_text)} | {p.unit} | "
                           f"{_cell(default)} | {_cell(p.accepts)} | {_cell(p.description)} |")
            out.append("")
    return "\n".join(out)
