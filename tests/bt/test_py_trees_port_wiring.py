"""Ports that py_trees wired before conversion keep their wiring through ``from_py_trees``.

py_trees wires a behaviour's ports with ``setup_ports()`` (the user's code, or py_trees' own
XML parser): remapped ports read and write the keys named, unremapped ones a key of the node's
own, constants given in XML a key holding the value. The converted tree reads and writes the
same entries, and ``to_xml`` writes that wiring.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, ClassVar

import py_trees
import pytest
from py_trees.common import Status
from py_trees.parsers.behaviour_tree_xml import parse_behaviour_tree_xml
from py_trees.ports import BehaviourWithPorts, PortInformation

from bt_manip.bt import from_py_trees, load_tree_string, to_xml
from bt_manip.bt.ports import Literal, Ref
from bt_manip.bt.pytrees.leaf import PyTreesLeaf
from bt_manip.bt.status import NodeStatus

Ports = dict[str, PortInformation]


class WiringScale(BehaviourWithPorts, register=False):
    """Write ``value * factor`` to ``scaled`` and "done" to ``note``."""

    INPUT_PORTS: ClassVar[Ports] = {
        "value": PortInformation(float), "factor": PortInformation(float, default_value=2.0)}
    OUTPUT_PORTS: ClassVar[Ports] = {
        "scaled": PortInformation(float), "note": PortInformation(str, default_value="idle")}

    def update(self) -> Status:
        self._set_output("scaled", self.get_input("value") * self.get_input("factor"))
        self._set_output("note", "done")
        return Status.SUCCESS


@pytest.fixture(autouse=True)
def own_py_trees_blackboard(monkeypatch: pytest.MonkeyPatch) -> None:
    for attribute in ("storage", "metadata", "clients"):
        monkeypatch.setattr(py_trees.blackboard.Blackboard, attribute, {})


def leaf(tree: Any) -> PyTreesLeaf:
    (found,) = [n for n in tree.root.iterate() if isinstance(n, PyTreesLeaf)]
    return found


def test_setup_ports_remappings_are_kept() -> None:
    scale = WiringScale(name="scale")
    scale.setup_ports(port_remappings={"value": "/in/value", "scaled": "out"},
                      subtree_namespace="/ns")
    own_key = scale._default_port_storage_key("note").lstrip("/")
    root = py_trees.composites.Sequence("root", memory=True, children=[scale])
    tree = from_py_trees(root, blackboard={"in/value": 3.0})
    bindings = leaf(tree).bindings
    assert bindings["value"] == Ref("in/value")
    assert bindings["scaled"] == Ref("ns/out")  # relative to the namespace, as py_trees does
    assert bindings["note"] == Ref(own_key)  # unremapped: the node's own key in py_trees
    assert tree.blackboard.get(own_key) == "idle"  # the default setup_ports() wrote
    assert tree.tick() is NodeStatus.SUCCESS
    assert tree.blackboard.get("ns/out") == 6.0  # factor: unwired, its declared default
    assert tree.blackboard.get(own_key) == "done"
    xml = to_xml(tree)
    assert 'value="{in/value}"' in xml
    assert 'scaled="{ns/out}"' in xml
    again = load_tree_string(xml, blackboard={"in/value": 4.0})
    assert again.tick() is NodeStatus.SUCCESS
    assert again.blackboard.get("ns/out") == 8.0


def test_constants_from_py_trees_xml_parser_are_kept(tmp_path: Path) -> None:
    path = tmp_path / "tree.xml"
    path.write_text('<root main_tree_to_execute="Main"><BehaviorTree ID="Main">'
                    '<Sequence name="seq"><WiringScale name="s" value="1.5" factor="3" '
                    'scaled="{result}"/></Sequence></BehaviorTree></root>')
    root = parse_behaviour_tree_xml(str(path), node_registry={"WiringScale": WiringScale})
    tree = from_py_trees(root)
    bindings = leaf(tree).bindings
    assert bindings["value"] == Literal(1.5)
    assert bindings["factor"] == Literal(3.0)
    assert bindings["scaled"] == Ref("result")
    constants = {k: tree.blackboard.get(k) for k in tree.blackboard.keys()  # noqa: SIM118
                 if k.endswith("__const")}
    assert sorted(constants.values()) == [1.5, 3.0]  # where py_trees' parser put them
    assert tree.tick() is NodeStatus.SUCCESS
    assert tree.blackboard.get("result") == 4.5
    xml = to_xml(tree)
    assert 'value="1.5"' in xml and 'factor="3.0"' in xml


def test_behaviour_not_set_up_has_no_wiring_to_carry() -> None:
    root = py_trees.composites.Sequence("root", memory=True,
                                        children=[WiringScale(name="scale")])
    with pytest.raises(ValueError, match="missing its required port 'value'"):
        from_py_trees(root)
