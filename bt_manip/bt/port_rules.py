"""Load-time checks of a tree beyond each port on its own: what is certain to fail.

- :func:`one_of_problem`: a node given none of the alternative ports it needs (``MoveToPose``
  with neither ``position`` nor ``object``), or several that exclude each other, as its class
  declares them (``REQUIRED_ONE_OF``, ``REQUIRED_ANY_OF``);
- :func:`world_name_problem`: a literal naming an object, body, model, pose or robot that the
  world to run on lacks (the class's ``WORLD_NAMES``; ``bt-manip validate --world W``);
- :func:`keys_used`: the blackboard keys a ``<BehaviorTree>`` reads or writes, so that a
  ``<SubTree>`` port its tree never uses (a typo) is reported as a warning.
"""

from __future__ import annotations

import re
from collections.abc import Mapping

from bt_manip.bt.attributes import closest
from bt_manip.bt.node import BtNode
from bt_manip.bt.ports import parse_reference
from bt_manip.bt.xml_parse import Element

WORLD_KINDS = ("object", "body", "model", "pose", "robot")
"""What a port of ``WORLD_NAMES`` may name (see :attr:`BtNode.WORLD_NAMES`)."""
_KIND_TEXT = {"object": "movable object", "body": "body", "model": "model", "pose": "named pose",
              "robot": "robot"}
_KIND_PLURAL = {"object": "movable objects", "body": "bodies", "model": "models",
                "pose": "named poses", "robot": "robots"}
_WORD = re.compile(r"[A-Za-z_@][A-Za-z0-9_]*")
_NUMBERS = re.compile(r"^\s*-?[\d.eE+-]+(\s*;\s*-?[\d.eE+-]+)+\s*$")


def _given(attributes: Mapping[str, str], port: str) -> bool:
    value = attributes.get(port)
    return value is not None and value.strip() != ""


def one_of_problem(cls: type[BtNode], attributes: Mapping[str, str]) -> list[str]:
    """Why the ports given in ``attributes`` miss the alternatives ``cls`` needs (one message
    per group of alternatives), or an empty list."""
    messages = []
    groups = [(g, True) for g in cls.REQUIRED_ONE_OF] + [(g, False) for g in cls.REQUIRED_ANY_OF]
    for group, exclusive in groups:
        alternatives = [alt.split("+") for alt in group]
        complete = [ports for ports in alternatives if all(_given(attributes, p) for p in ports)]
        shown = " or ".join(" and ".join(f'{p}="..."' for p in ports) for ports in alternatives)
        if not complete:
            partial = [p for ports in alternatives if any(_given(attributes, q) for q in ports)
                       for p in ports if not _given(attributes, p)]
            missing = f" ({', '.join(partial)} missing)" if partial else ""
            messages.append(f"{cls.NODE_ID} needs {shown}{missing}; it would fail when ticked")
        elif exclusive and len(complete) > 1 and all(
            parse_reference(attributes[p]) is None for ports in complete for p in ports
        ):
            given = " and ".join("+".join(ports) for ports in complete)
            messages.append(f"{cls.NODE_ID} takes exactly one of {shown}, got {given}; it "
                            "would fail when ticked")
    return messages


def world_name_problem(cls: type[BtNode], attributes: Mapping[str, str],
                       names: Mapping[str, set[str]], world: str) -> list[str]:
    """Literals of ``cls``'s ``WORLD_NAMES`` ports that name nothing of that kind in
    ``names`` (kind -> names the world ``world`` has); blackboard references pass."""
    messages = []
    for port, kind in cls.WORLD_NAMES.items():
        value = attributes.get(port)
        if value is None or value.strip() == "" or parse_reference(value) is not None:
            continue
        if kind == "pose" and _NUMBERS.match(value):
            continue
        known = names.get(kind, set())
        if value not in known:
            listed = ", ".join(sorted(known)[:12]) or "none"
            messages.append(
                f"{cls.NODE_ID} {port}=\"{value}\": {world} has no {_KIND_TEXT[kind]} of that "
                f"name{closest(value, known)}; its {_KIND_PLURAL[kind]}: {listed}")
    return messages


def keys_used(tree: Element, port_defaults: Mapping[str, set[str]]) -> set[str] | None:
    """The blackboard keys a ``<BehaviorTree>`` element's nodes may read or write: every word
    of every attribute value (references, scripts, and a nested SubTree's remapping), the names
    of ports bound with ``{=}``, and the keys a node reads by default (``port_defaults``, by
    node ID). None when the tree passes its whole blackboard on (``_autoremap``), so that any
    key may be used."""
    used: set[str] = set()
    stack = list(tree.children)
    while stack:
        element = stack.pop()
        stack.extend(element.children)
        node_id = element.get("ID") if element.tag in ("SubTree", "Action", "Condition",
                                                        "Control", "Decorator") else None
        used |= port_defaults.get(node_id or element.tag, set())
        for name, value in element.attrib.items():
            if name == "_autoremap" and value.strip().lower() in ("true", "1"):
                return None
            if name in ("ID", "name"):
                continue
            if parse_reference(value) == "=":
                used.add(name)
            used.update(w.lstrip("@") for w in _WORD.findall(value))
    return used
