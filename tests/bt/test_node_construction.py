"""Building a node: bt-manip asks py_trees' abstract-class question once per node class, and a
node gets the same fields as py_trees' ``PortsMixin.__init__`` gives it."""

from __future__ import annotations

import abc
from typing import Any, ClassVar

import py_trees
import pytest
from py_trees.common import Status
from py_trees.ports import PortInformation, PortsMixin

from bt_manip.bt.controls import Sequence
from bt_manip.bt.decorators import Inverter
from bt_manip.bt.node import _ABSTRACT_FLAG, ActionNode, BtNode


class Probe(ActionNode):
    INPUT_PORTS: ClassVar[dict[str, PortInformation]] = {  # type: ignore[misc]  # py_trees stub: not ClassVar
        "x": PortInformation(int, False, "a number", 3),
    }

    def update(self) -> Status:
        return Status.SUCCESS


class ProbeChild(Probe):
    pass


class HalfDone(ActionNode):
    @abc.abstractmethod
    def plan(self) -> None: ...


def _ports_fields(node: Any) -> dict[str, Any]:
    return {k: getattr(node, k) for k in
            ("_blackboard_client", "_subtree_namespace", "_ports_logger", "_behaviour_class_name")}


def _as_py_trees_builds(cls: type[BtNode], *args: Any, **kwargs: Any) -> Any:
    """A node of ``cls`` built by py_trees' own ``PortsMixin.__init__`` (then bt-manip's)."""
    node = cls.__new__(cls)
    PortsMixin.__init__(node, *args, **kwargs)
    return node


def test_a_node_gets_the_fields_py_trees_gives_it() -> None:
    ours = Probe("p")
    theirs = _as_py_trees_builds(Probe, "p")
    assert _ports_fields(ours) == _ports_fields(theirs)
    assert ours._behaviour_class_name == "Probe"
    behaviour_fields = set(vars(theirs))
    assert behaviour_fields <= set(vars(ours))
    assert ours.name == theirs.name == "p" and ours.status is theirs.status
    assert ours.get_input("x") == 3
    control = Sequence("c", children=[Probe("a")])
    decorator = Inverter("d", child=Probe("b"))
    for node in (control, decorator):
        assert _ports_fields(node)["_behaviour_class_name"] == type(node).__name__
        assert node.children and node.children[0].parent is node


def test_the_abstract_question_is_asked_once_per_class(monkeypatch: pytest.MonkeyPatch) -> None:
    import bt_manip.bt.node as node_module

    asked: list[type] = []
    real = node_module._ports_class_is_abstract

    def counting(cls: type) -> bool:
        asked.append(cls)
        return real(cls)

    monkeypatch.setattr(node_module, "_ports_class_is_abstract", counting)
    for cls in (Probe, ProbeChild):
        monkeypatch.delattr(cls, _ABSTRACT_FLAG, raising=False)
    for _ in range(3):
        Probe("p")
        ProbeChild("q")
    assert asked == [Probe, ProbeChild]       # each class its own answer, kept on the class
    assert vars(Probe)[_ABSTRACT_FLAG] is False and vars(ProbeChild)[_ABSTRACT_FLAG] is False


def test_an_abstract_node_class_cannot_be_built(monkeypatch: pytest.MonkeyPatch) -> None:
    with pytest.raises(TypeError, match="abstract"):
        HalfDone("h")
    assert py_trees.ports._ports_class_is_abstract(HalfDone)

    class Undeclared(ProbeChild):
        pass

    # the answer kept on the class is what construction obeys, with py_trees' message
    monkeypatch.setattr(Undeclared, _ABSTRACT_FLAG, True, raising=False)
    with pytest.raises(TypeError, match="without the INPUT_PORTS and OUTPUT_PORTS"):
        Undeclared("u")


class Listed(ActionNode):
    INPUT_PORTS: ClassVar[dict[str, PortInformation]] = {  # type: ignore[misc]  # py_trees stub: not ClassVar
        "n": PortInformation(int, False, "a number", 3),
        "values": PortInformation(list[float], False, "numbers", []),
        "key": PortInformation(str, False, "an entry", ""),
    }

    def update(self) -> Status:
        return Status.SUCCESS


def test_repeated_text_attributes_are_checked_once_and_never_shared() -> None:
    from bt_manip.bt.attributes import _CHECKS_FLAG, _CHECKS_PER_CLASS

    text = {"n": "5", "key": "{entry}"}
    first = Listed.check_attributes(text)
    again = Listed.check_attributes(text)
    assert again == first and again.bindings is not first.bindings
    assert tuple(text.items()) in vars(Listed)[_CHECKS_FLAG]
    a, b = Listed("a", **text), Listed("b", **text)
    assert a.bindings == b.bindings and a.bindings is not b.bindings
    assert a.attribute_texts is not b.attribute_texts
    del a.bindings["n"]                          # one node's bindings are its own
    assert b.get_input("n") == 5 and Listed("c", **text).get_input("n") == 5
    assert a.get_input("n") == 3
    # a list literal is converted for each node: nodes never hold the same list
    with_list = {"values": "1;2;3"}
    c, d = Listed("c", **with_list), Listed("d", **with_list)
    assert c.get_input("values") == d.get_input("values") == [1.0, 2.0, 3.0]
    assert c.get_input("values") is not d.get_input("values")
    assert tuple(with_list.items()) not in vars(Listed)[_CHECKS_FLAG]
    # errors are reported every time, and not kept
    with pytest.raises(ValueError, match="'m' is not a port of Listed"):
        Listed("e", m="1")
    with pytest.raises(ValueError, match="'m' is not a port of Listed"):
        Listed("e", m="1")
    for i in range(_CHECKS_PER_CLASS + 10):
        Listed.check_attributes({"n": str(i)})
    assert len(vars(Listed)[_CHECKS_FLAG]) <= _CHECKS_PER_CLASS
