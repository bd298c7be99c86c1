"""Trees built in Python: same classes as XML; to_xml then load_tree gives the same tree."""

from __future__ import annotations

from bt_manip.bt import BtNode, SubTree, Tree, TreeContext, load_tree_string, to_xml
from bt_manip.bt.controls import Fallback, ReactiveSequence, Sequence
from bt_manip.bt.decorators import Repeat, RetryUntilSuccessful, Timeout
from bt_manip.bt.leaves import AlwaysFailure, Script, ScriptCondition, Sleep
from bt_manip.clock import ManualClock


def shape(node: BtNode) -> tuple:  # type: ignore[type-arg]
    sub = (node.tree_id,) if isinstance(node, SubTree) else ()
    return (node.NODE_ID, node.name, *sub, tuple(sorted(node.attribute_texts.items())),
            tuple(shape(c) for c in node.bt_children()))


def build() -> Tree:
    talk = Sequence(children=[Script(code="said := msg .. '!'"), AlwaysFailure(_skipIf="true")])
    root = Sequence("main", children=[
        Script(code="n := 0"),
        Repeat(num_cycles=3, child=Script(code="n += 1")),
        RetryUntilSuccessful(num_attempts="{tries}", child=ScriptCondition(code="n == 3")),
        Fallback(children=[AlwaysFailure(_onFailure="f := 1"),
                           Timeout(msec=500, child=Sleep(msec=100))]),
        SubTree("Talk", child=talk, msg="hi", said="{out}"),
        ReactiveSequence(children=[ScriptCondition(code="true"), Script(code="done := true")]),
    ])
    return Tree(root, context=TreeContext(clock=ManualClock()), blackboard={"tries": 2})


def run(tree: Tree) -> dict:  # type: ignore[type-arg]
    clock = tree.context.clock
    statuses = []
    for _ in range(4):
        tree.tick()
        statuses.append(tree.bt_status.value)
        clock.advance(0.05)  # type: ignore[attr-defined]
    return {"statuses": statuses, "bb": tree.blackboard.as_dict()}


def test_python_tree_runs() -> None:
    result = run(build())
    assert result["statuses"] == ["RUNNING", "RUNNING", "SUCCESS", "RUNNING"]
    assert result["bb"] == {"tries": 2, "n": 3, "f": 1, "out": "hi!", "done": True}


def test_round_trip_gives_the_same_tree() -> None:
    original = build()
    text = to_xml(original)
    assert 'BTCPP_format="4"' in text and '<BehaviorTree ID="Talk">' in text
    loaded = load_tree_string(text, context=TreeContext(clock=ManualClock()),
                              blackboard={"tries": 2})
    assert shape(loaded.root) == shape(original.root)
    assert run(loaded) == run(build())
    assert to_xml(loaded) == text


def test_typed_python_values_and_errors() -> None:
    node = Repeat(num_cycles=2, child=Script(code="a := 1"))
    assert node.get_input("num_cycles") == 2
    assert node.attribute_texts == {"num_cycles": "2"}
    try:
        Repeat(num_cycle=2, child=Script(code="a := 1"))
    except ValueError as e:
        assert "did you mean 'num_cycles'" in str(e)
    else:
        raise AssertionError("unknown port accepted")
