"""Every user-input error of issue 3 item 6: file:line, a hint, all problems in one run."""

from __future__ import annotations

from pathlib import Path

import pytest
from bt_harness import wrap

from bt_manip.bt import load_tree, load_tree_string, validate_file
from bt_manip.errors import InputError


def problems_of(tmp_path: Path, text: str, name: str = "t.xml") -> list[str]:
    path = tmp_path / name
    path.write_text(text)
    return [str(p) for p in validate_file(str(path))]


def test_malformed_xml(tmp_path: Path) -> None:
    out = problems_of(tmp_path, '<root BTCPP_format="4">\n<BehaviorTree ID="M">\n<Sequence>\n'
                                "</BehaviorTree></root>")
    assert len(out) == 1
    assert out[0].startswith(f"{tmp_path / 't.xml'}:4:")
    assert "malformed XML: mismatched tag" in out[0]


def test_entities_and_doctype_refused(tmp_path: Path) -> None:
    out = problems_of(tmp_path, '<!DOCTYPE root [<!ENTITY x SYSTEM "file:///etc/passwd">]>'
                                '<root BTCPP_format="4">&x;</root>')
    assert len(out) == 1 and "DOCTYPE" in out[0] and "refused" in out[0]


def test_unknown_node_suggests_closest(tmp_path: Path) -> None:
    out = problems_of(tmp_path, wrap("<Sequence>\n<AlwaysSucess/></Sequence>"))
    assert len(out) == 1
    assert ":2: unknown node 'AlwaysSucess' (did you mean 'AlwaysSuccess'" in out[0]


def test_a_tree_used_as_a_node_is_told_how_to_call_it(tmp_path: Path) -> None:
    # BehaviorTree.CPP refuses <Sub/> too ("Node not recognized"); the message says the fix
    out = problems_of(tmp_path, '<root BTCPP_format="4" main_tree_to_execute="M">\n'
                                '<BehaviorTree ID="M"><Sequence>\n<Sub/></Sequence>'
                                '</BehaviorTree>\n<BehaviorTree ID="Sub"><AlwaysSuccess/>'
                                "</BehaviorTree></root>")
    assert out == [f"{tmp_path / 't.xml'}:3: unknown node 'Sub': it is a <BehaviorTree> of "
                   'this document; call it with <SubTree ID="Sub"/>']


def test_attribute_not_a_port(tmp_path: Path) -> None:
    out = problems_of(tmp_path, wrap('<Repeat num_cycles="2" cycles="3"><AlwaysSuccess/></Repeat>'))
    assert out == [f"{tmp_path / 't.xml'}:1: 'cycles' is not a port of Repeat (did you mean "
                   "'num_cycles'?); its ports are: num_cycles"]


def test_missing_required_port(tmp_path: Path) -> None:
    out = problems_of(tmp_path, wrap("<Delay><AlwaysSuccess/></Delay>"))
    assert len(out) == 1 and "Delay is missing its required port 'delay_msec'" in out[0]


@pytest.mark.parametrize("xml, expected", [
    ('<RetryUntilSuccessful num_attempts="three"><AlwaysSuccess/></RetryUntilSuccessful>',
     "bad value for port 'num_attempts' of RetryUntilSuccessful: expected an integer, got 'three'"),
    ('<RunOnce then_skip="maybe"><AlwaysSuccess/></RunOnce>',
     "bad value for port 'then_skip' of RunOnce: expected true or false, got 'maybe'"),
    ('<Precondition if="true" else="DONE"><AlwaysSuccess/></Precondition>',
     "bad value for port 'else' of Precondition: expected one of SUCCESS, FAILURE"),
])
def test_bad_literal_for_typed_port(tmp_path: Path, xml: str, expected: str) -> None:
    out = problems_of(tmp_path, wrap(xml))
    assert len(out) == 1 and expected in out[0]


@pytest.mark.parametrize("xml, expected", [
    ("<Inverter><AlwaysSuccess/><AlwaysFailure/></Inverter>",
     "Inverter must have exactly 1 child, found 2"),
    ("<AlwaysSuccess><AlwaysFailure/></AlwaysSuccess>",
     "AlwaysSuccess is a leaf and takes no children, found 1"),
    ("<IfThenElse><AlwaysSuccess/></IfThenElse>", "IfThenElse must have 2 to 3 children, found 1"),
    ("<Sequence/>", "Sequence must have at least 1 child, found 0"),
    ('<Switch2 variable="a" case_1="a" case_2="b"><AlwaysSuccess/></Switch2>',
     "Switch2 must have exactly 3 children, found 1"),
])
def test_wrong_number_of_children(tmp_path: Path, xml: str, expected: str) -> None:
    out = problems_of(tmp_path, wrap(xml))
    assert len(out) == 1 and expected in out[0]


def test_undefined_subtree(tmp_path: Path) -> None:
    out = problems_of(tmp_path, wrap('<SubTree ID="Grasp"/>', '<BehaviorTree ID="Grab">'
                                                              '<AlwaysSuccess/></BehaviorTree>'))
    assert len(out) == 1
    assert "SubTree 'Grasp' is not defined (did you mean 'Grab'?)" in out[0]


def test_recursive_subtree(tmp_path: Path) -> None:
    text = ('<root BTCPP_format="4" main_tree_to_execute="A">\n'
            '<BehaviorTree ID="A"><SubTree ID="B"/></BehaviorTree>\n'
            '<BehaviorTree ID="B"><Sequence><AlwaysSuccess/>\n<SubTree ID="A"/></Sequence>'
            "</BehaviorTree>\n</root>")
    out = problems_of(tmp_path, text)
    assert out == [f"{tmp_path / 't.xml'}:4: recursive SubTree: A -> B -> A; "
                   "a tree cannot contain itself"]


def test_include_cycle_and_missing_include(tmp_path: Path) -> None:
    (tmp_path / "b.xml").write_text('<root BTCPP_format="4">\n<include path="a.xml"/>\n'
                                    '<BehaviorTree ID="B"><AlwaysSuccess/></BehaviorTree></root>')
    (tmp_path / "a.xml").write_text(
        '<root BTCPP_format="4" main_tree_to_execute="A">\n<include path="b.xml"/>\n'
        '<include path="nowhere/c.xml"/>\n'
        '<BehaviorTree ID="A"><SubTree ID="B"/></BehaviorTree></root>')
    out = [str(p) for p in validate_file(str(tmp_path / "a.xml"))]
    assert len(out) == 2, out
    assert any(o.startswith(f"{tmp_path / 'a.xml'}:3: included file 'nowhere/c.xml' not found")
               for o in out)
    assert any(o.startswith(f"{tmp_path / 'b.xml'}:2: include cycle: a.xml -> b.xml -> a.xml")
               for o in out)


def test_include_relative_to_including_file(tmp_path: Path) -> None:
    sub = tmp_path / "sub"
    sub.mkdir()
    (sub / "leaf.xml").write_text('<root BTCPP_format="4"><BehaviorTree ID="Leaf">'
                                  '<Script code="@x := 5"/></BehaviorTree></root>')
    (sub / "mid.xml").write_text('<root BTCPP_format="4"><include path="leaf.xml"/></root>')
    (tmp_path / "main.xml").write_text(
        '<root BTCPP_format="4" main_tree_to_execute="M"><include path="sub/mid.xml"/>'
        '<BehaviorTree ID="M"><SubTree ID="Leaf"/></BehaviorTree></root>')
    tree = load_tree(str(tmp_path / "main.xml"))
    tree.tick()
    assert tree.blackboard.as_dict() == {"x": 5}


def test_script_syntax_error_has_column(tmp_path: Path) -> None:
    out = problems_of(tmp_path, wrap('<Sequence>\n<Script code="a := (1 + 2"/>\n'
                                     '<AlwaysSuccess _skipIf="x =="/></Sequence>'))
    assert len(out) == 2
    assert out[0].endswith(":2: script syntax error in code of Script: expected ')', found end "
                           "of script (column 12 of the script)")
    assert ":3: script syntax error in _skipIf of AlwaysSuccess" in out[1]
    assert "(column 5 of the script)" in out[1]


def test_all_problems_in_one_run(tmp_path: Path) -> None:
    out = problems_of(tmp_path, wrap("<Sequence>\n<Foo/>\n<Timeout msecs=\"5\"><AlwaysSuccess/>"
                                     "</Timeout>\n<ForceSuccess/>\n<SubTree ID=\"Nope\"/>"
                                     "</Sequence>"))
    lines = [o.split(":")[1] for o in out]
    assert lines == ["2", "3", "3", "4", "5"]


def test_load_tree_raises_input_error_with_every_problem() -> None:
    with pytest.raises(InputError) as info:
        load_tree_string(wrap("<Sequence><Nope/><Inverter/></Sequence>"))
    assert len(info.value.problems) == 2


def test_main_tree_selection_errors() -> None:
    two = ('<root BTCPP_format="4"><BehaviorTree ID="A"><AlwaysSuccess/></BehaviorTree>'
           '<BehaviorTree ID="B"><AlwaysFailure/></BehaviorTree></root>')
    with pytest.raises(InputError, match="several trees and no main_tree_to_execute"):
        load_tree_string(two)
    assert load_tree_string(two, tree_id="B").tick().name == "FAILURE"
    with pytest.raises(InputError, match="--tree-id names tree 'C'"):
        load_tree_string(two, tree_id="C")


def test_version_3_converted_other_versions_rejected_and_missing_format_warns() -> None:
    # BehaviorTree.CPP v3 files are read through the v3 -> v4 conversion (bt/v3_convert.py)
    v3 = load_tree_string('<root BTCPP_format="3"><BehaviorTree ID="A"><SequenceStar>'
                          "<AlwaysSuccess/></SequenceStar></BehaviorTree></root>")
    assert v3.tick().name == "SUCCESS"
    assert any("SequenceStar -> SequenceWithMemory" in str(w)
               for w in v3.warnings)  # type: ignore[attr-defined]
    with pytest.raises(InputError, match='BTCPP_format="2" is not supported'):
        load_tree_string('<root BTCPP_format="2"><BehaviorTree ID="A"><AlwaysSuccess/>'
                         "</BehaviorTree></root>")
    tree = load_tree_string('<root><BehaviorTree ID="A"><AlwaysSuccess/></BehaviorTree></root>')
    assert "no BTCPP_format" in str(tree.warnings[0])  # type: ignore[attr-defined]


def test_output_port_needs_reference_and_explicit_form() -> None:
    tree = load_tree_string(wrap('<Control ID="Sequence" name="seq"><Action ID="AlwaysSuccess"/>'
                                 "</Control>"))
    assert tree.root.name == "seq" and tree.tick().name == "SUCCESS"
    with pytest.raises(InputError, match="'Sequence' is a Control, not a Action"):
        load_tree_string(wrap('<Action ID="Sequence"><AlwaysSuccess/></Action>'))


def test_depth_bound(tmp_path: Path) -> None:
    deep = "<Inverter>" * 300 + "<AlwaysSuccess/>" + "</Inverter>" * 300
    out = problems_of(tmp_path, wrap(deep))
    assert len(out) == 1 and "nested deeper than 256 levels" in out[0]


def test_script_runtime_errors_name_the_node() -> None:
    from bt_manip.bt import TreeRuntimeError

    tree = load_tree_string(wrap('<Sequence><Script name="bump" code="missing = 1"/></Sequence>'))
    with pytest.raises(TreeRuntimeError, match=r"Script 'bump'.*does not exist yet; use :="):
        tree.tick()
    tree = load_tree_string(wrap('<ScriptCondition code="nowhere &gt; 1"/>'))
    with pytest.raises(TreeRuntimeError, match="variable not found: nowhere"):
        tree.tick()
