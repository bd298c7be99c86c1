"""Trees as other projects write them (BehaviorTree.CPP's tutorials and tests, tree editors,
Nav2's model file), on bt-manip and on the real BehaviorTree.CPP 4.8.2 (``behaviortreepy``).

Each case is the smallest tree showing one habit of real files that bt-manip used to refuse,
or ran otherwise than BT.CPP: both engines must give the same status and root blackboard, or
both refuse the tree. BT.CPP runs in a worker process (it prints on stdout and may abort). The
wake-up loop shapes run through ``bt-manip run`` in a subprocess with a time-out, so that a
regression fails instead of hanging the suite.
"""

from __future__ import annotations

import json
import subprocess
import sys
import textwrap
from pathlib import Path
from typing import Any

import pytest

import bt_manip.behaviours  # noqa: F401  # registers Navigate, which test 9 shadows
from bt_manip.bt import NodeStatus, TreeContext, load_tree_string
from bt_manip.bt.xml_loader import validate
from bt_manip.bt.xml_parse import XmlError, parse_xml_text
from bt_manip.clock import ManualClock
from bt_manip.errors import InputError

ROOT = Path(__file__).resolve().parents[2]
SAMPLES = ROOT.parent / "shared" / "samples"
TABLE = ROOT / "worlds" / "sawyer_table.yaml"

_WORKER = textwrap.dedent("""
    import json, sys
    import behaviortreepy as bt
    xml, init, main, out = sys.argv[1], json.loads(sys.argv[2]), sys.argv[3], sys.argv[4]
    def answer(result):
        with open(out, "w") as f:
            json.dump(result, f)
    factory = bt.BehaviorTreeFactory()
    bb = bt.Blackboard.create()
    setters = {bool: bb.set_bool, int: bb.set_int, float: bb.set_double, str: bb.set_string}
    for key, value in init.items():
        setters[type(value)](key, value)
    try:
        factory.register_behavior_tree_from_text(xml)
        tree = (factory.create_tree(main, bb) if main
                else factory.create_tree_from_text(xml, bb))
    except Exception as e:
        answer({"refused": str(e)})
        sys.exit(0)
    try:
        status = tree.tick_while_running().name
    except Exception as e:
        answer({"error": str(e)})
        sys.exit(0)
    values = {}
    for key in bb.get_keys():
        try:
            values[key] = bb.get_string(key)
        except Exception:
            pass
    answer({"status": status, "bb": values})
""")


def btcpp(xml: str, tmp_path: Path, init: dict[str, Any] | None = None,
          main: str = "") -> dict[str, Any]:
    """Run ``xml`` on BehaviorTree.CPP in a worker process: ``status`` and ``bb`` (text), or
    ``refused`` (building failed) or ``error`` (ticking threw)."""
    pytest.importorskip("behaviortreepy")
    out = tmp_path / "btcpp.json"
    subprocess.run([sys.executable, "-c", _WORKER, xml, json.dumps(init or {}), main, str(out)],
                   stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, timeout=60,
                   check=False)
    assert out.exists(), "the BehaviorTree.CPP worker died"
    return json.loads(out.read_text())  # type: ignore[no-any-return]


def ours(xml: str, init: dict[str, Any] | None = None, main: str = "") -> dict[str, Any]:
    """The same on bt-manip (on a clock that does not move; these trees wait on no timer)."""
    try:
        tree = load_tree_string(xml, tree_id=main or None, blackboard=dict(init or {}),
                                context=TreeContext(clock=ManualClock()))
    except InputError as e:
        return {"refused": str(e)}
    try:
        status = tree.tick_while_running(10_000).name
    except Exception as e:  # a script or port error while ticking, as BT.CPP throws
        return {"error": str(e)}
    return {"status": status, "bb": {k: str(v) for k, v in tree.blackboard.as_dict().items()}}


def _value(text: str) -> float | str:
    """A blackboard value read back as text, compared as a number when it is one (BT.CPP
    writes a double as "2.000000", bt-manip's text of it is "2.0"; true is 1 in both)."""
    if text in ("True", "False"):
        return float(text == "True")
    try:
        return float(text)
    except ValueError:
        return text


def same(xml: str, tmp_path: Path, init: dict[str, Any] | None = None,
         main: str = "") -> dict[str, Any]:
    """Both engines agree: the same status and blackboard, or both refuse, or both throw."""
    theirs, mine = btcpp(xml, tmp_path, init, main), ours(xml, init, main)
    for outcome in ("refused", "error"):
        if outcome in theirs or outcome in mine:
            assert outcome in theirs and outcome in mine, (theirs, mine)
            return mine
    assert mine["status"] == theirs["status"]
    assert {k: _value(v) for k, v in mine["bb"].items()} == {
        k: _value(v) for k, v in theirs["bb"].items()}
    return mine


def root(body: str, head: str = "") -> str:
    return f'{head}<root BTCPP_format="4">{body}</root>'


# 2. A single <BehaviorTree> without an ID (tutorials t08, t09, t12; most BT.CPP test trees)

def test_the_only_tree_of_a_file_needs_no_id(tmp_path: Path) -> None:
    xml = root('<BehaviorTree><Sequence><Script code="a := 1"/><Script code="b := a + 1"/>'
               '</Sequence></BehaviorTree>')
    assert same(xml, tmp_path)["status"] == "SUCCESS"
    assert load_tree_string(xml).tree_id == "BehaviorTree_0"  # BT.CPP's name for it


def test_two_trees_without_an_id_are_refused_by_both(tmp_path: Path) -> None:
    xml = root('<BehaviorTree><AlwaysSuccess/></BehaviorTree>'
               '<BehaviorTree ID="X"><AlwaysSuccess/></BehaviorTree>')
    same(xml, tmp_path, main="X")
    assert "needs an ID when a file has several" in ours(xml, main="X")["refused"]


# 3. Raw &&, < and > in attribute values, text before <root> (tutorial t09)

RAW = ('// clang-format off\n' + root(
    '<BehaviorTree ID="M"><Sequence>'
    '<Script code="A := 1; B := 0; s := \'&amp;&lt;\'"/>'
    '<Precondition if="A>-B && A<2" else="FAILURE"><Script code="c := 3"/></Precondition>'
    '<Script code="d := 4" _skipIf="A<2"/>'
    '<Script code="e := A > 0 && B < 1"/>'
    '</Sequence></BehaviorTree>'))


def test_raw_operators_in_attributes_and_text_before_root_read_as_btcpp_reads_them(
        tmp_path: Path) -> None:
    result = same(RAW, tmp_path, main="M")
    assert result["status"] == "SUCCESS"
    assert result["bb"]["c"] == "3" and "d" not in result["bb"]
    assert result["bb"]["s"] == "&<"  # the references still read as references


def test_lenient_reading_keeps_lines_and_columns() -> None:
    text = ('// clang-format off\n<root BTCPP_format="4">\n'
            '  <BehaviorTree ID="M"><Sequence a="x<y && z">\n'
            '    <B c="1<2"/><C/></Sequence></BehaviorTree></root>')
    strict = ('                   \n' + text.split("\n", 1)[1]).replace("<y", "-y").replace(
        "&&", "--").replace("1<2", "1-2")  # the same places in a strictly valid document

    def places(element: Any) -> list[tuple[str, int, int]]:
        return [(element.tag, element.line, element.column)] + [
            place for child in element.children for place in places(child)]

    lenient = parse_xml_text(text, "t.xml")
    assert places(lenient) == places(parse_xml_text(strict, "t.xml"))
    seq = lenient.children[0].children[0]
    assert (seq.line, seq.attrib["a"], seq.children[0].attrib["c"]) == (3, "x<y && z", "1<2")


def test_a_byte_order_mark_and_declaration_stay_before_a_lenient_document() -> None:
    text = '\ufeff<?xml version="1.0" encoding="UTF-8"?>\n<root a="x && y"><B/></root>'
    assert parse_xml_text(text.encode("utf-8"), "t.xml").attrib["a"] == "x && y"


def test_what_tinyxml2_refuses_too_stays_refused_with_its_line() -> None:
    cases = {
        '<root BTCPP_format="4">\n<A x="1<2">\n</B></root>': 3,  # mismatched tag
        '<root BTCPP_format="4"/>\n// trailing text\n': 2,  # text after the document
        '<root a="&&">\n<!DOCTYPE x>\n</root>': 2,  # still no DOCTYPE
    }
    for text, line in cases.items():
        with pytest.raises(XmlError) as info:
            parse_xml_text(text, "t.xml")
        assert info.value.problem.line == line, text


def test_big_hostile_documents_are_refused_or_read_with_their_position() -> None:
    with pytest.raises(XmlError) as info:  # a lenient reading of 2 MB of broken tags
        parse_xml_text('<root a="&&">' + '<a b="' * 350_000, "t.xml")
    assert info.value.problem.line == 1
    with pytest.raises(XmlError) as info:
        parse_xml_text("<" * 2_000_000 + "&", "t.xml")
    assert info.value.problem.line == 1
    many = '<root a="x<y">' + '<a b="1<2"/>' * 150_000 + "</root>"
    assert len(parse_xml_text(many, "t.xml").children) == 150_000


# 4. Attributes starting with _ that are no pre/post-conditions (tree editors, _not_da_port)

def test_underscore_attributes_are_kept_as_non_port_attributes(tmp_path: Path) -> None:
    xml = root('<BehaviorTree ID="M"><Sequence _collapsed="true">'
               '<Script code="a := 1" _not_da_port="whatever"/>'
               '<SubTree ID="S" _collapsed="false"/></Sequence></BehaviorTree>'
               '<BehaviorTree ID="S"><Script code="b := 2"/></BehaviorTree>')
    assert same(xml, tmp_path, main="M")["status"] == "SUCCESS"


def test_a_misspelt_condition_script_is_ignored_by_both(tmp_path: Path) -> None:
    xml = root('<BehaviorTree ID="M"><Script code="a := 1" _skipif="true"/></BehaviorTree>')
    assert same(xml, tmp_path, main="M")["bb"] == {"a": "1"}


# 5. A SubTree's literal port with _autoremap is the subtree's own entry

def test_a_literal_subtree_port_with_autoremap_stays_in_the_subtree(tmp_path: Path) -> None:
    xml = root('<BehaviorTree ID="M"><Sequence><Script code="v := 1"/>'
               '<SubTree ID="Sub" _autoremap="true" v="7"/></Sequence></BehaviorTree>'
               '<BehaviorTree ID="Sub"><Script code="w := v"/></BehaviorTree>')
    result = same(xml, tmp_path, main="M")
    assert result == {"status": "SUCCESS", "bb": {"v": "1", "w": "7"}}


# 6. SubTree port defaults from <TreeNodesModel> (tutorial t14_subtree_model)

def subtree_model(body: str, in_port: str = '<input_port name="in_v" default="42"/>') -> str:
    return ('<root BTCPP_format="4" main_tree_to_execute="M">'
            f'<BehaviorTree ID="M"><Sequence>{body}</Sequence></BehaviorTree>'
            '<BehaviorTree ID="Sub"><Script code="out_v := in_v"/></BehaviorTree>'
            f'<TreeNodesModel><SubTree ID="Sub">{in_port}'
            '<output_port name="out_v" default="{output}"/></SubTree></TreeNodesModel></root>')


@pytest.mark.parametrize("body", [
    '<SubTree ID="Sub"/>',
    '<SubTree ID="Sub" in_v="5"/>',
    '<SubTree ID="Sub" out_v="{o2}"/>',
    '<Script code="src := 9"/><SubTree ID="Sub" in_v="{src}"/>',
    '<Script code="in_v := 3"/><SubTree ID="Sub" _autoremap="true"/>',
    '<SubTree ID="Sub" _autoremap="true"/>',  # the model is not used: both throw
])
def test_subtree_model_defaults_remap_the_ports_not_given(body: str, tmp_path: Path) -> None:
    same(subtree_model(body), tmp_path)


def test_subtree_model_default_gives_btcpp_tutorial_result(tmp_path: Path) -> None:
    assert same(subtree_model('<SubTree ID="Sub"/>'), tmp_path)["bb"] == {"output": "42"}


def test_a_subtree_model_port_without_default_must_be_given(tmp_path: Path) -> None:
    xml = subtree_model('<SubTree ID="Sub"/>', '<input_port name="in_v"/>')
    same(xml, tmp_path)
    assert "does not remap port 'in_v'" in ours(xml)["refused"]
    assert same(subtree_model('<SubTree ID="Sub" in_v="5"/>', '<input_port name="in_v"/>'),
                tmp_path)["bb"] == {"output": "5"}


# 7. A Loop over a queue entry that has no value

@pytest.mark.parametrize("loop", ["LoopInt", "LoopDouble", "LoopString", "LoopBool"])
def test_a_loop_over_an_entry_without_a_value_is_an_error(loop: str, tmp_path: Path) -> None:
    xml = root(f'<BehaviorTree ID="M"><{loop} queue="{{q}}" value="{{x}}"><AlwaysSuccess/>'
               f'</{loop}></BehaviorTree>')
    assert "error" in same(xml, tmp_path, main="M")
    assert "queue entry 'q' has no value" in ours(xml, main="M")["error"]


# 8. Nav2's current model file, with a <bidirectional_port>

def test_nav2_main_model_file_is_read() -> None:
    models = SAMPLES / "nav2" / "main" / "nav2_tree_nodes.xml"
    if not models.exists():
        pytest.skip(f"the samples are not here ({SAMPLES})")
    tree = SAMPLES / "nav2" / "main" / "navigate_to_pose_w_bounds_check.xml"
    problems, _ = validate(str(tree), [str(models)])
    assert not [p for p in problems if p.file == str(models)], problems


def test_bidirectional_port_reads_as_an_inout_port(tmp_path: Path) -> None:
    xml = root('<BehaviorTree ID="M"><Mine idx="{i}"/></BehaviorTree><TreeNodesModel>'
               '<Action ID="Mine"><bidirectional_port name="idx" type="int"/></Action>'
               '</TreeNodesModel>')
    path = tmp_path / "t.xml"
    path.write_text(xml)
    problems, _ = validate(str(path))
    assert problems == []


# 9. A TreeNodesModel entry shadowed by a bt-manip node

def test_a_shadowed_model_entry_is_named_in_a_warning_and_in_the_port_error(
        tmp_path: Path) -> None:
    path = tmp_path / "t.xml"
    path.write_text('<root BTCPP_format="4" main_tree_to_execute="M">\n'
                    '<BehaviorTree ID="M"><Navigate target="kitchen" goal="0;0;0"/>'
                    '</BehaviorTree>\n<TreeNodesModel>\n'
                    '  <Action ID="Navigate"><input_port name="target"/></Action>\n'
                    '</TreeNodesModel></root>\n')
    problems, warnings = validate(str(path))
    assert [(w.file, w.line) for w in warnings] == [(str(path), 4)]
    assert "bt-manip's own node Navigate (bt_manip." in warnings[0].message
    assert "has no port 'target'" in warnings[0].message
    assert [p.line for p in problems] == [2]
    assert problems[0].message.startswith("'target' is not a port of Navigate")
    assert f"the TreeNodesModel entry at {path}:4 declares another 'Navigate'" in (
        problems[0].message)


def test_a_model_entry_with_the_ports_of_the_bt_manip_node_gives_no_warning(
        tmp_path: Path) -> None:
    path = tmp_path / "t.xml"
    path.write_text(root('<BehaviorTree ID="M"><Navigate goal="0;0;0"/></BehaviorTree>'
                         '<TreeNodesModel><Action ID="Navigate"><input_port name="goal"/>'
                         '</Action></TreeNodesModel>'))
    assert validate(str(path)) == ([], [])


# The refusals that are right stay

@pytest.mark.parametrize("body", [
    '<IfThenElse><AlwaysSuccess/></IfThenElse>',
    '<WhileDoElse><AlwaysSuccess/><AlwaysSuccess/><AlwaysSuccess/><AlwaysSuccess/>'
    '</WhileDoElse>',
    '<SomeoneElsesNode/>',
])
def test_trees_btcpp_refuses_stay_refused(body: str, tmp_path: Path) -> None:
    xml = root(f'<BehaviorTree ID="M">{body}</BehaviorTree>')
    theirs = btcpp(xml, tmp_path, main="M")  # at build, or at the first tick (child counts)
    assert "refused" in theirs or "error" in theirs
    assert "refused" in ours(xml, main="M")


def test_a_recursive_subtree_stays_refused() -> None:
    xml = root('<BehaviorTree ID="M"><SubTree ID="M"/></BehaviorTree>')  # BT.CPP: overflows
    assert "recursi" in ours(xml, main="M")["refused"].lower()


# 1. Wake-up loops: timers fire and budgets hold

HANGS = {
    "retry": ('<Timeout msec="500"><RetryUntilSuccessful num_attempts="-1">'
              '<ScriptCondition code="ready == true"/></RetryUntilSuccessful></Timeout>'),
    "repeat": ('<Timeout msec="300"><Repeat num_cycles="-1"><AlwaysSuccess/></Repeat>'
               '</Timeout>'),
}
PAUSE_WITH_RETRY = ('<Parallel success_count="1" failure_count="1"><Sleep msec="100"/>'
                    '<RetryUntilSuccessful num_attempts="-1"><AlwaysFailure/>'
                    '</RetryUntilSuccessful></Parallel>')


def cli(tmp_path: Path, body: str, *args: str) -> tuple[int, dict[str, Any]]:
    """``bt-manip run`` in a subprocess (time-out: a hang fails the test): exit code, report."""
    tree, report = tmp_path / "tree.xml", tmp_path / "report.json"
    tree.write_text(root(f'<BehaviorTree ID="M">{body}</BehaviorTree>'))
    code = subprocess.run(
        [sys.executable, "-c", "import sys; from bt_manip.cli import main; "
         "sys.exit(main(sys.argv[1:]))", "run", str(tree), "--quiet", "--report", str(report),
         *args], cwd=ROOT, timeout=300, capture_output=True, check=False).returncode
    return code, json.loads(report.read_text())


@pytest.mark.parametrize("world", [False, True], ids=["wall-clock", "world"])
@pytest.mark.parametrize("shape", sorted(HANGS))
def test_a_timeout_ends_an_endless_wake_up_loop(shape: str, world: bool, tmp_path: Path) -> None:
    args = ["--bb", "ready=false"] + (["--world", str(TABLE)] if world else [])
    code, report = cli(tmp_path, HANGS[shape], *args)
    assert (code, report["status"]) == (1, "FAILURE")
    assert "timed out" in report["reason"]
    budget = {"retry": 0.5, "repeat": 0.3}[shape]
    assert report["sim_time"] >= budget - 0.06  # a timer does not fire early
    assert report["ticks"] >= 1


def test_btcpp_ends_the_same_wake_up_loops_with_failure(tmp_path: Path) -> None:
    for shape, body in HANGS.items():
        xml = root(f'<BehaviorTree ID="M">{body}</BehaviorTree>')
        assert btcpp(xml, tmp_path, {"ready": False}, "M")["status"] == "FAILURE", shape
    xml = root(f'<BehaviorTree ID="M">{PAUSE_WITH_RETRY}</BehaviorTree>')
    assert btcpp(xml, tmp_path, main="M")["status"] == "SUCCESS"


@pytest.mark.parametrize("world", [False, True], ids=["wall-clock", "world"])
def test_a_sleep_beside_an_endless_retry_ends_the_parallel(world: bool, tmp_path: Path) -> None:
    args = ["--world", str(TABLE)] if world else []
    code, report = cli(tmp_path, PAUSE_WITH_RETRY, *args)
    assert (code, report["status"]) == (0, "SUCCESS")  # BT.CPP's Parallel.PauseWithRetry


@pytest.mark.parametrize("world", [False, True], ids=["wall-clock", "world"])
def test_budgets_stop_an_unbounded_wake_up_loop(world: bool, tmp_path: Path) -> None:
    body = '<Repeat num_cycles="-1"><AlwaysSuccess/></Repeat>'
    args = ["--world", str(TABLE)] if world else []
    code, report = cli(tmp_path, body, "--max-ticks", "3", *args)
    assert (code, report["status"], report["ticks"]) == (1, "BUDGET", 3)
    code, report = cli(tmp_path, body, "--max-sim-time", "0.2", *args)
    assert (code, report["status"]) == (1, "BUDGET")
    assert "time budget of 0.2 s spent" in report["reason"]


def test_tick_returns_to_its_caller_after_max_wake_ups() -> None:
    tree = load_tree_string(root('<BehaviorTree ID="M"><Repeat num_cycles="2500">'
                                 '<Script code="n += 1"/></Repeat></BehaviorTree>'),
                            blackboard={"n": 0}, context=TreeContext(clock=ManualClock()))
    assert tree.tick() is NodeStatus.RUNNING  # the signal is kept: the next tick goes on
    assert tree.blackboard.get("n") == tree.max_wake_ups + 1
    assert tree.tick() is NodeStatus.RUNNING
    assert tree.tick() is NodeStatus.SUCCESS
    assert tree.blackboard.get("n") == 2500
