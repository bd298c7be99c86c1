"""Objects of the program's own classes as py_trees constructor arguments in XML.

A class is trusted by the program registering it (``registry.register_value_type``): ``to_xml``
writes its objects as ``{"$type": NAME, "state": {attributes}}`` and ``load_tree`` builds one
only for a registered name. User dicts keep their meaning (a ``$type`` key is escaped), an
attribute JSON cannot hold is refused when writing, and an unregistered name is a load error
(exit 2 through the CLI).
"""

from __future__ import annotations

import json
import re
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import py_trees
import pytest

from bt_manip.bt import NodeStatus, from_py_trees, load_tree_string, registry, to_xml
from bt_manip.bt.pytrees.values import MAX_DEPTH
from bt_manip.bt.tree import Tree
from bt_manip.cli import main
from bt_manip.errors import InputError


class Point:
    """A value type of these tests: plain attributes, an ``__init__`` that needs arguments."""

    def __init__(self, x: float, y: float) -> None:
        self.x, self.y = x, y


class Route:
    """A value type holding others."""

    def __init__(self, name: str, stops: list[Point], meta: dict[str, Any]) -> None:
        self.name, self.stops, self.meta = name, stops, meta


class Opaque:
    """Never registered."""


class Slotted:
    __slots__ = ("x",)


class Tagged(dict[str, Any]):
    pass


@pytest.fixture(autouse=True)
def own_blackboard(monkeypatch: pytest.MonkeyPatch) -> Iterator[None]:
    """py_trees' global blackboard emptied for the test, then restored; the registrations the
    tests make removed afterwards."""
    storage = py_trees.blackboard.Blackboard
    for attribute in ("storage", "metadata", "clients"):
        monkeypatch.setattr(storage, attribute, {})
    check = "CheckBlackboardVariableValue"
    had_check = registry.get(check) is not None
    registry.register(py_trees.behaviours.CheckBlackboardVariableValue)
    yield
    for name in ("Point", "Route", "geo.Point"):
        registry.unregister_value_type(name)
    if not had_check:
        registry.unregister(check)


@pytest.fixture
def trusted() -> None:
    registry.register_value_type(Point)
    registry.register_value_type(Route)


def setter(value: Any) -> Tree:
    """A converted py_trees tree setting blackboard entry ``v`` to ``value``."""
    return from_py_trees(py_trees.behaviours.SetBlackboardVariable(
        name="set", variable_name="v", variable_value=value, overwrite=True))


def round_trip(value: Any) -> tuple[str, Any]:
    """The XML of a tree setting ``value``, and the value the loaded tree sets."""
    text = to_xml(setter(value))
    tree = load_tree_string(text)
    assert tree.tick() is NodeStatus.SUCCESS
    return text, tree.blackboard.get("v")


def tree_xml(body: str) -> str:
    return f'<root BTCPP_format="4">\n<BehaviorTree ID="Main">\n{body}\n</BehaviorTree>\n</root>'


def set_v(json_text: str) -> str:
    return tree_xml(f"<SetBlackboardVariable variable_name=\"v\" variable_value='{json_text}' "
                    'overwrite="true"/>')


# -------------------------------------------------------------------- writing and loading


def test_a_registered_value_loads_as_a_new_object_of_its_class(trusted: None) -> None:
    original = Point(1.5, -2)
    text, value = round_trip(original)
    assert """variable_value='{"$type": "Point", "state": {"x": 1.5, "y": -2}}'""" in text
    assert type(value) is Point and value is not original
    assert vars(value) == {"x": 1.5, "y": -2}


def test_the_loaded_node_sets_one_object_at_every_tick_as_py_trees_does(trusted: None) -> None:
    tree = load_tree_string(to_xml(setter(Point(0, 0))))
    tree.tick()
    first = tree.blackboard.get("v")
    first.x = 9  # py_trees' SetBlackboardVariable hands out the object it was given
    tree.tick()
    assert tree.blackboard.get("v") is first and first.x == 9


def test_values_inside_values_lists_and_dicts(trusted: None) -> None:
    route = Route("r1", [Point(0, 0), Point(1, 2)], {"$type": "not a value", "n": [1, None]})
    _text, value = round_trip(route)
    assert type(value) is Route and value.name == "r1"
    assert [type(p) for p in value.stops] == [Point, Point]
    assert [vars(p) for p in value.stops] == [{"x": 0, "y": 0}, {"x": 1, "y": 2}]
    assert value.meta == {"$type": "not a value", "n": [1, None]}
    _text, listed = round_trip([Point(3, 4), {"k": Point(5, 6)}])
    assert vars(listed[0]) == {"x": 3, "y": 4} and vars(listed[1]["k"]) == {"x": 5, "y": 6}


def test_py_trees_reads_and_writes_attributes_of_the_loaded_object(trusted: None) -> None:
    tree = load_tree_string(tree_xml(
        '<Sequence>\n'
        """<SetBlackboardVariable variable_name="goal" variable_value='{"$type": "Point", """
        """"state": {"x": 1, "y": 2}}' overwrite="true"/>\n"""
        '<SetBlackboardVariable variable_name="goal.x" variable_value="7" overwrite="true"/>\n'
        """<CheckBlackboardVariableValue check='{"variable": "goal.x", "value": 7, """
        """"operator": "eq"}'/>\n"""
        '</Sequence>'))
    assert tree.tick() is NodeStatus.SUCCESS
    goal = tree.blackboard.get("goal")
    assert type(goal) is Point and vars(goal) == {"x": 7, "y": 2}


def test_a_value_type_registered_under_a_name_of_its_own() -> None:
    registry.register_value_type(Point, name="geo.Point")
    text, value = round_trip(Point(1, 1))
    assert '"$type": "geo.Point"' in text and type(value) is Point


# -------------------------------------------------------------------- user data


@pytest.mark.parametrize("user", [
    {"$type": "Point", "state": {"x": 1, "y": 2}},
    {"$$type": 1, "$typed": 2, "type": 3, "$": 4, "nested": {"$type": "Point", "state": {}}},
])
def test_a_user_dict_that_looks_like_a_value_stays_a_dict(trusted: None,
                                                          user: dict[str, Any]) -> None:
    text, value = round_trip(user)
    assert type(value) is dict and value == user
    assert '"$$type"' in text


@pytest.mark.parametrize(("written", "loaded"), [
    ('{"$$type": "Point"}', {"$type": "Point"}),
    ('{"$$$type": 1, "$types": 2}', {"$$type": 1, "$types": 2}),
    ('{"type": "Point", "state": {}}', {"type": "Point", "state": {}}),
])
def test_hand_written_escapes_load_as_documented(trusted: None, written: str,
                                                 loaded: dict[str, Any]) -> None:
    tree = load_tree_string(set_v(written))
    tree.tick()
    assert tree.blackboard.get("v") == loaded


# -------------------------------------------------------------------- refusals


def test_an_unregistered_value_type_is_a_load_error_naming_file_line_node_and_type() -> None:
    registry.register_value_type(Point)
    text = to_xml(setter(Point(1, 2)))
    registry.unregister_value_type("Point")
    line = next(n for n, t in enumerate(text.splitlines(), 1) if "SetBlackboardVariable " in t)
    with pytest.raises(InputError) as raised:
        load_tree_string(text)
    message = str(raised.value)
    assert message.startswith(
        f"<string>:{line}: bad value for parameter 'variable_value' of SetBlackboardVariable: "
        "value type 'Point' is not registered")
    assert "registry.register_value_type(Point)" in message and "--import" in message
    assert message.count("\n") == 0  # one problem, no other reading of the text tried


@pytest.mark.parametrize(("written", "problem"), [
    ('{"$type": "Point", "state": {}, "note": 1}',
     'an object with the key "$type" is a value of a registered type, {"$type": NAME, '
     '"state": {...}}, got the keys ["$type", "note", "state"]; for a key named "$type" write '
     '"$$type"'),
    ('{"$type": "Point"}', 'got the keys ["$type"]'),
    ('{"$type": 3, "state": {}}', '"$type" names a value type, got 3'),
    ('{"$type": "Point", "state": [1, 2]}',
     'the "state" of a Point is a JSON object of its attributes, got [1, 2]'),
    ('[{"$type": "Nowhere", "state": {}}]', "value type 'Nowhere' is not registered"),
    ('{"$type": "Now\\nhere' + "x" * 100 + '", "state": {}}',
     "value type 'Now\\nhere" + "x" * 51 + "...' is not registered"),
])
def test_malformed_values_are_load_errors(trusted: None, written: str, problem: str) -> None:
    with pytest.raises(InputError) as raised:
        load_tree_string(set_v(written))
    message = str(raised.value)
    assert message.startswith(
        "<string>:3: bad value for parameter 'variable_value' of SetBlackboardVariable: ")
    assert problem in message


@pytest.mark.parametrize("depth", [MAX_DEPTH + 1, 100_000])
def test_json_nested_too_deeply_is_a_load_error(depth: int) -> None:
    with pytest.raises(InputError) as raised:
        load_tree_string(set_v("[" * depth + "]" * depth))
    assert str(raised.value) == (
        "<string>:3: bad value for parameter 'variable_value' of SetBlackboardVariable: the JSON "
        f"is nested more than {MAX_DEPTH} levels deep")
    tree = load_tree_string(set_v("[" * MAX_DEPTH + "]" * MAX_DEPTH))  # as deep as allowed
    tree.tick()
    value, levels = tree.blackboard.get("v"), 1
    while value:
        (value,), levels = value, levels + 1
    assert levels == MAX_DEPTH


def test_the_deepest_value_that_is_written_loads_back(trusted: None) -> None:
    written = None
    for depth in range(MAX_DEPTH):
        nested: Any = 1
        for _ in range(depth):
            nested = [nested]
        try:
            written = (depth, to_xml(setter(Point(nested, 0))))
        except ValueError as e:
            assert "the Point's attribute 'x'" in str(e) and "levels deep" in str(e)
            break
    assert written is not None and written[0] > MAX_DEPTH // 2
    tree = load_tree_string(written[1])
    tree.tick()
    value = tree.blackboard.get("v")
    for _ in range(written[0]):
        value.x = value.x[0]
    assert value.x == 1


def test_an_object_of_an_unregistered_class_is_not_written() -> None:
    with pytest.raises(ValueError) as raised:
        to_xml(setter(Opaque()))
    assert str(raised.value).endswith(
        "its argument 'variable_value': a Opaque cannot be written in XML; to write it as its "
        "attributes, register its class: registry.register_value_type(Opaque)")
    assert "'set'" in str(raised.value)


@pytest.mark.parametrize(("attribute", "problem"), [
    ({1, 2}, "the Point's attribute 'x' is a set, which would not load back as one"),
    ((1, 2), "the Point's attribute 'x' is a tuple, which would not load back as one"),
    ({"a": Opaque()}, "the Point's attribute 'x'['a'] is a Opaque, which would not load back"),
    ({3: "three"}, "the Point's attribute 'x' has the key 3, a int; JSON keys are text"),
    ([[Route("r", [], {})]], "the Point's attribute 'x'[0][0] is a Route, which would not load"),
])
def test_a_value_whose_attributes_are_not_json_is_not_written(attribute: Any,
                                                              problem: str) -> None:
    registry.register_value_type(Point)  # Route is not
    with pytest.raises(ValueError) as raised:
        to_xml(setter(Point(attribute, 0)))
    message = str(raised.value)
    assert message.startswith("cannot write ") and "'set'" in message
    assert f"its argument 'variable_value': {problem}" in message


def test_a_value_that_holds_itself_is_not_written(trusted: None) -> None:
    loop = Point(0, 0)
    loop.x = [loop]
    with pytest.raises(ValueError, match="nested more than 100 levels deep"):
        to_xml(setter(loop))


def test_what_cannot_be_a_value_type() -> None:
    registry.register_value_type(Point)
    registry.register_value_type(Point)  # again: nothing changes
    other = type("Point", (), {"__module__": "elsewhere"})
    with pytest.raises(ValueError, match=re.escape(
            f"value type 'Point' is already registered by {__name__}.Point")):
        registry.register_value_type(other)
    with pytest.raises(TypeError, match="objects of Slotted keep no __dict__"):
        registry.register_value_type(Slotted)
    with pytest.raises(TypeError, match="Tagged subclasses dict"):
        registry.register_value_type(Tagged)
    with pytest.raises(TypeError, match=r"is a node class: register it with registry\.register"):
        registry.register_value_type(py_trees.behaviours.Success)
    with pytest.raises(TypeError, match="is not a class"):
        registry.register_value_type(Point(0, 0))  # type: ignore[type-var]
    assert registry.value_types() == {"Point": Point}


# -------------------------------------------------------------------- through the CLI

PLUGIN = """\
from bt_manip.bt import registry


@registry.register_value_type
class Point:
    def __init__(self, x, y):
        self.x, self.y = x, y
"""


def test_cli_validate_and_run_refuse_an_unregistered_type_and_take_one_from_import(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    tree = tmp_path / "goal.xml"
    tree.write_text(set_v('{"$type": "Point", "state": {"x": 1.5, "y": -2}}'))
    plugin = tmp_path / "points.py"
    plugin.write_text(PLUGIN)
    expected = (f"{tree}:3: bad value for parameter 'variable_value' of SetBlackboardVariable: "
                "value type 'Point' is not registered")
    for verb in ("validate", "run"):
        assert main([verb, str(tree)]) == 2
        err = capsys.readouterr().err
        assert err.startswith(expected) and "Traceback" not in err
    assert main(["validate", str(tree), "--import", str(plugin)]) == 0
    assert capsys.readouterr().out == f"{tree}: OK\n"
    bb_out = tmp_path / "bb.json"
    assert main(["run", str(tree), "--quiet", "--import", str(plugin),
                 "--bb-out", str(bb_out)]) == 0
    assert "result: SUCCESS" in capsys.readouterr().out.splitlines()
    # the blackboard file writes the value as the XML does
    assert json.loads(bb_out.read_text())["v"] == {"$type": "Point",
                                                   "state": {"x": 1.5, "y": -2}}
