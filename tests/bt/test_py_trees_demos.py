"""py_trees' own demos tick the same through bt-manip, node by node, tick by tick.

Every demo program of the installed py_trees (``py_trees.demos``) that builds a tree is built
without running its ``main()`` (its ``create_root()``/``create_tree()``, or the tree its
``main()`` would build), then ticked four ways (:mod:`tests.bt.py_trees_side_by_side`): by
py_trees, by ``from_py_trees(root)``, by ``from_py_trees(root, builtins=False)`` and as the
XML ``to_xml`` writes, loaded back. After every tick each node's status, the leaves' calls and
the blackboard must agree. With BT.CPP built-ins (and so in XML), py_trees' extra
``terminate(INVALID)`` on a child that had already finished is left out (documented).

The blackboard demo sets an object of its own ``Nested`` class as a value: its XML holds it as
``{"$type": "Nested", "state": {...}}`` and loads back because the test, as the program loading
the file, registers ``Nested`` as a value type; without that, ``to_xml`` refuses to write it.
"""

from __future__ import annotations

import importlib
import operator
from collections.abc import Callable
from pathlib import Path
from typing import Any

import py_trees
import pytest
from py_trees.parsers.behaviour_tree_xml import parse_behaviour_tree_xml

from bt_manip.bt import from_py_trees, registry, to_xml
from tests.bt.py_trees_side_by_side import (
    WAYS,
    differences,
    fresh_blackboard,
    normalised,
    run_way,
)

TICKS = 12
Demo = tuple[Callable[[], py_trees.behaviour.Behaviour], dict[str, Any], bool]


def demo(name: str) -> Any:
    return importlib.import_module(f"py_trees.demos.{name}")


class FakeConnection:
    """The action demo's pipe to its planning process: 10% more done at every poll."""

    def __init__(self) -> None:
        self.done = 0

    def send(self, _message: Any) -> None:
        self.done = 0

    def poll(self) -> bool:
        return self.done < 100

    def recv(self) -> list[int]:
        self.done += 10
        return [self.done]


class FakeProcess:
    def __init__(self, *_args: Any, **_kwargs: Any) -> None:
        pass

    def start(self) -> None:
        pass

    def terminate(self) -> None:
        pass


def action_root() -> py_trees.behaviour.Behaviour:
    """The action demo's behaviour, its planning process replaced by a fake pipe."""
    module = demo("action")
    return module.Action(name="Action")


def ports_basic() -> py_trees.behaviour.Behaviour:
    module = demo("ports.basic")
    root = py_trees.composites.Sequence("Basic", memory=True)
    node = module.Multiply(name="mul")
    node.setup_ports(port_remappings={"a": "/numbers/a", "b": "/numbers/b",
                                      "product": "/numbers/product"}, subtree_namespace="/")
    root.add_child(node)
    return root


def ports_remapping() -> py_trees.behaviour.Behaviour:
    """The remapping demo's two pipelines (ticked one node after the other by the demo), as
    two sequences of a sequence."""
    module = demo("ports.remapping")
    root = py_trees.composites.Sequence("Pipelines", memory=True)
    for namespace, prefix in (("/pipeline_a", "alpha"), ("/pipeline_b", "beta")):
        steps = [module.GenerateValue(name="step1_generate", prefix=prefix),
                 module.AppendSuffix(name="step2_append_suffix", suffix="_done"),
                 module.ReadResult(name="step3_read_result")]
        remaps = [{"value": "/step1_value"},
                  {"text_in": "/step1_value", "text_out": "/step2_value"},
                  {"value": "/step2_value"}]
        for step, remap in zip(steps, remaps, strict=True):
            step.setup_ports(port_remappings=remap, subtree_namespace=namespace)
        pipeline = py_trees.composites.Sequence(namespace.strip("/"), memory=True)
        pipeline.add_children(steps)
        root.add_child(pipeline)
    return root


def ports_xml(name: str) -> Callable[[], py_trees.behaviour.Behaviour]:
    def build() -> py_trees.behaviour.Behaviour:
        demo(f"ports.{name}")
        path = Path(demo("ports").__file__).with_name(f"{name}.xml")
        return parse_behaviour_tree_xml(str(path))
    return build


def demos() -> dict[str, Demo]:
    """Each demo's tree factory, the blackboard its ``main()`` seeds, and whether it needs
    ``setup()``."""
    return {
        "action": (action_root, {}, True),
        "blackboard": (lambda: demo("blackboard").create_root(),
                       {"/dude": "Bob", "/parameters/default_speed": 30.0}, True),
        "blackboard_remappings": (lambda: demo("blackboard_remappings").Remap(
            name="Remap", remap_to={"/foo/bar/wow": "/parameters/wow"}), {}, False),
        "context_switching": (lambda: demo("context_switching").create_root(), {}, True),
        "display_modes": (lambda: demo("display_modes").create_root(), {}, False),
        "dot_graphs": (lambda: demo("dot_graphs").create_tree("all"), {}, False),
        "either_or": (lambda: demo("either_or").create_root(), {}, True),
        "eternal_guard": (lambda: demo("eternal_guard").create_root(), {}, True),
        "lifecycle": (lambda: demo("lifecycle").Counter(), {}, True),
        "logging": (lambda: demo("logging").create_tree(), {}, True),
        "pick_up_where_you_left_off": (
            lambda: demo("pick_up_where_you_left_off").create_root(), {}, True),
        "selector": (lambda: demo("selector").create_root(), {}, True),
        "sequence": (lambda: demo("sequence").create_root(), {}, True),
        "stewardship": (lambda: demo("stewardship").create_tree(), {}, True),
        # py_trees' ports, wired by setup_ports() (the demo's or py_trees' XML parser's)
        "ports_basic": (ports_basic, {"/numbers/a": 2.5, "/numbers/b": 4.0}, False),
        "ports_remapping": (ports_remapping, {}, False),
        "ports_xml_tree": (ports_xml("xml_tree"), {}, False),
        "ports_nested_subtrees": (ports_xml("nested_subtrees"), {}, False),
    }


DEMOS = demos()
VALUE_TYPES = {"blackboard": ["Nested"]}
"""The classes of each demo that its XML holds objects of: registered as value types while the
demos run (the loading program trusts them), so that ``to_xml`` writes them and ``load_tree``
builds them."""
REFUSED_UNREGISTERED = {
    "blackboard": "argument 'variable_value': a Nested cannot be written in XML",
}
"""What ``to_xml`` says for each demo while its value types are not registered."""


@pytest.fixture(autouse=True)
def quiet_demos(monkeypatch: pytest.MonkeyPatch) -> Any:
    """No sleeping, no planning process, py_trees' blackboard restored afterwards."""
    action = demo("action")
    monkeypatch.setattr(action.multiprocessing, "Pipe", lambda: (FakeConnection(), None))
    monkeypatch.setattr(action.multiprocessing, "Process", FakeProcess)
    monkeypatch.setattr(action.atexit, "register", lambda *_a, **_k: None)
    monkeypatch.setattr(action.time, "sleep", lambda _s: None)
    storage = py_trees.blackboard.Blackboard
    for attribute in ("storage", "metadata", "clients"):
        monkeypatch.setattr(storage, attribute, {})
    trusted = [getattr(demo(name), cls) for name, classes in VALUE_TYPES.items()
               for cls in classes]
    for cls in trusted:
        registry.register_value_type(cls)
    yield
    for cls in trusted:
        registry.unregister_value_type(cls.__qualname__)
    _ = operator  # (the demos compare with operator functions)


def mismatches(name: str) -> dict[str, list[str]]:
    factory, seed_bb, setup = DEMOS[name]
    runs = {way: normalised(run_way(way, factory, TICKS, seed_bb, setup)) for way in WAYS}
    found = {}
    for way in WAYS[1:]:
        # the XML holds BT.CPP built-ins: it must tick as the converted tree it was written from
        expected = runs["builtins" if way == "xml" else "py_trees"]
        problems = list(differences(expected, runs[way], strict_calls=way == "py_trees_nodes",
                                    bt_view=way == "xml"))
        if problems:
            found[way] = problems
    return found


@pytest.mark.parametrize("name", sorted(DEMOS))
def test_demo_ticks_alike_four_ways(name: str) -> None:
    assert mismatches(name) == {}


def test_every_demo_with_a_tree_is_covered() -> None:
    folder = Path(demo("action").__file__).parent
    programs = {p.stem for p in folder.glob("*.py") if p.stem != "__init__"}
    programs |= {f"ports_{p.stem}" for p in (folder / "ports").glob("*.py")
                 if p.stem != "__init__"}
    without_a_tree = {"blackboard_namespaces"}  # its main() only writes to clients
    assert programs - without_a_tree == set(DEMOS)


def test_the_demo_trees_are_registered_after_conversion() -> None:
    """The demos' own behaviour classes get IDs, so their XML loads back."""
    fresh_blackboard({})
    tree = from_py_trees(demo("context_switching").create_root())
    assert registry.get("ContextSwitch") is not None
    assert '<ContextSwitch name="Context"/>' in to_xml(tree)


def test_a_user_class_named_like_a_py_trees_class_is_written_by_its_module() -> None:
    """stewardship's own ``SuccessEveryN`` is not py_trees' ``SuccessEveryN``."""
    fresh_blackboard({})
    xml = to_xml(from_py_trees(demo("stewardship").create_tree()))
    assert '<py_trees.demos.stewardship.SuccessEveryN name="EveryN"/>' in xml
    assert registry.get("SuccessEveryN").BEHAVIOUR is py_trees.behaviours.SuccessEveryN


def test_remap_to_is_read_back_from_the_behaviours_client() -> None:
    """The remappings demo's ``Remap`` keeps ``remap_to`` only in its blackboard client."""
    fresh_blackboard({})
    factory, _seed, _setup = DEMOS["blackboard_remappings"]
    xml = to_xml(from_py_trees(factory()))
    assert """<Remap remap_to='{"/foo/bar/wow": "/parameters/wow"}'/>""" in xml


def test_the_demos_value_types_are_written_by_name_and_attributes() -> None:
    fresh_blackboard({})
    xml = to_xml(from_py_trees(demo("blackboard").create_root()))
    assert """variable_value='{"$type": "Nested", "state": {"foo": "bar"}}'""" in xml


@pytest.mark.parametrize("name", sorted(REFUSED_UNREGISTERED))
def test_to_xml_refuses_what_would_load_with_another_meaning(name: str) -> None:
    for cls in VALUE_TYPES[name]:
        registry.unregister_value_type(cls)
    factory, _seed, _setup = DEMOS[name]
    fresh_blackboard({})
    tree = from_py_trees(factory())
    with pytest.raises(ValueError, match="cannot write") as raised:
        to_xml(tree)
    assert REFUSED_UNREGISTERED[name] in str(raised.value)
