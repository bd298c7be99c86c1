"""BehaviorTree.CPP v3 -> v4 conversion (bt/v3_convert.py), the ``convert`` verb
(the convert verb, bt_manip/cli/convert.py) and loading v3 files directly."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

import bt_manip.nav2  # noqa: F401  (registers the Nav2 nodes Humble's trees use)
from bt_manip.bt import load_tree
from bt_manip.bt.v3_convert import ConvertError, convert_v3
from bt_manip.bt.walk import walk_nodes
from bt_manip.cli import main

ROOT = Path(__file__).resolve().parents[2]
HUMBLE = ROOT.parent / "shared" / "samples" / "nav2" / "humble"

V3 = """<root main_tree_to_execute="A">
  <BehaviorTree ID="A">
    <Control ID="SequenceStar" name="seq">
      <Action ID="AlwaysSuccess"/>
      <Parallel threshold="1">
        <Condition ID="AlwaysSuccess" name="c"/>
        <SubTree ID="B" __shared_blackboard="true"/>
      </Parallel>
      <Decorator ID="RetryUntilSuccesful" num_attempts="2">
        <SubTreePlus ID="B" __autoremap="1"/>
      </Decorator>
    </Control>
  </BehaviorTree>
  <BehaviorTree ID="B"><AlwaysSuccess/></BehaviorTree>
  <TreeNodesModel><Action ID="Custom"/></TreeNodesModel>
</root>
"""


def test_convert_rewrites_each_v3_form_keeping_lines() -> None:
    v4, rewrites = convert_v3(V3)
    assert v4.count("\n") == V3.count("\n")
    assert '<root BTCPP_format="4" main_tree_to_execute="A">' in v4
    assert '<SequenceWithMemory name="seq">' in v4 and "</SequenceWithMemory>" in v4
    assert "<AlwaysSuccess/>" in v4 and '<AlwaysSuccess name="c"/>' in v4
    assert '<Parallel success_count="1">' in v4
    assert '<SubTree ID="B" _autoremap="true"/>' in v4
    assert '<RetryUntilSuccessful num_attempts="2">' in v4 and "</RetryUntilSuccessful>" in v4
    assert '<SubTree ID="B" _autoremap="1"/>' in v4
    assert '<TreeNodesModel><Action ID="Custom"/></TreeNodesModel>' in v4  # declarations stay
    assert (3, "SequenceStar -> SequenceWithMemory") in rewrites
    assert (5, "Parallel threshold -> success_count") in rewrites
    assert (7, "SubTree __shared_blackboard -> _autoremap") in rewrites
    assert (10, "SubTreePlus -> SubTree") in rewrites
    assert (1, 'no BTCPP_format -> BTCPP_format="4"') in rewrites


def test_convert_keeps_v4_text_and_rejects_malformed_xml() -> None:
    v4 = '<root BTCPP_format="4"><BehaviorTree ID="A"><AlwaysSuccess/></BehaviorTree></root>'
    assert convert_v3(v4) == (v4, [])
    assert convert_v3(v4.replace('"4"', '"3"'))[0] == v4
    with pytest.raises(ConvertError) as info:
        convert_v3("<root>\n<BehaviorTree ID='A'>\n<Sequence>\n</BehaviorTree></root>")
    assert info.value.line == 4


def run_convert(*argv: str) -> int:
    """``bt-manip convert ARGV...`` through the command line's entry point."""
    return main(["convert", *argv])


def test_convert_verb_writes_v4_and_lists_rewrites(tmp_path: Path,
                                                   capsys: pytest.CaptureFixture[str]) -> None:
    src = tmp_path / "v3.xml"
    src.write_text(V3)
    assert run_convert(str(src)) == 0
    out, err = capsys.readouterr()
    assert out == convert_v3(V3)[0]
    assert f"{src}:3: SequenceStar -> SequenceWithMemory" in err.splitlines()
    dest = tmp_path / "v4.xml"
    assert run_convert(str(src), "-o", str(dest)) == 0
    assert dest.read_text() == out and src.read_text() == V3
    assert run_convert(str(src), "-o", str(src)) == 2  # never over the input
    assert src.read_text() == V3
    bad = tmp_path / "bad.xml"
    bad.write_text("<root>\n<BehaviorTree>\n</root>\n")
    assert run_convert(str(bad)) == 2
    assert f"{bad}:3:" in capsys.readouterr().err
    assert run_convert(str(tmp_path / "missing.xml")) == 2


def test_run_and_validate_load_v3_with_a_warning_per_rewrite(tmp_path: Path) -> None:
    src = tmp_path / "v3.xml"
    src.write_text(V3)
    tree = load_tree(str(src))
    assert tree.tick().name == "SUCCESS"
    warnings = [str(w) for w in tree.warnings]  # type: ignore[attr-defined]
    assert any(":1: warning: <root> has no BTCPP_format" in w for w in warnings)
    assert any(":3: warning: v3 form: SequenceStar -> SequenceWithMemory" in w
               for w in warnings)


def test_v3_dollar_references_and_a_greater_than_in_a_value(tmp_path: Path) -> None:
    # v3 reads "${key}" as a blackboard reference, spaces around it stripped; a ">" in a
    # quoted value is legal XML and does not end the tag
    src = tmp_path / "dollar.xml"
    src.write_text("""<root main_tree_to_execute="A">
  <BehaviorTree ID="A">
    <Sequence name="a>b">
      <SetBlackboard output_key="x" value="3"/>
      <SetBlackboard output_key="y" value=" ${x} "/>
      <Action ID="SetBlackboard" name="${x}" output_key="z" value="${x}"/>
    </Sequence>
  </BehaviorTree>
  <TreeNodesModel>
    <Action ID="Custom"><output_port name="out" type="std::vector&lt;int> >"/></Action>
  </TreeNodesModel>
</root>
""")
    v4, rewrites = convert_v3(src.read_text())
    assert '<Sequence name="a>b">' in v4 and "</Sequence>" in v4 and v4.endswith("</root>\n")
    assert '<SetBlackboard output_key="y" value="{x}"/>' in v4
    assert '<SetBlackboard name="${x}" output_key="z" value="{x}"/>' in v4  # a name stays
    assert '<output_port name="out" type="std::vector&lt;int> >"/>' in v4
    assert (5, "value: ${x} -> {x}") in rewrites and (6, "value: ${x} -> {x}") in rewrites
    out = tmp_path / "bb.json"
    code = main(["run", str(src), "--quiet", "--bb-out", str(out)])
    assert code == 0
    assert {k: v for k, v in json.loads(out.read_text()).items() if k in "xyz"} == {
        "x": "3", "y": "3", "z": "3"}


def test_v3_files_are_read_as_leniently_as_v4_ones(tmp_path: Path,
                                                   capsys: pytest.CaptureFixture) -> None:
    # BehaviorTree.CPP's parser takes text before the first element and a raw "<" in a
    # value; the loader takes them in v4 files, convert and the v3 path take them too
    lead = tmp_path / "lead.xml"
    lead.write_text('// clang-format off\n<root>\n  <BehaviorTree ID="A">\n'
                    '    <Precondition if="1 < 2" else="FAILURE"><AlwaysSuccess/></Precondition>\n'
                    '  </BehaviorTree>\n</root>\n')
    assert main(["validate", str(lead)]) == 0
    capsys.readouterr()
    assert main(["convert", str(lead)]) == 0
    out = capsys.readouterr().out
    assert out.startswith('// clang-format off\n<root BTCPP_format="4">')
    broken = tmp_path / "broken.xml"
    broken.write_text("<root>\n  <BehaviorTree ID=\"A\">\n    <AlwaysSuccess>\n"
                      "  </BehaviorTree>\n</root>\n")
    assert main(["validate", str(broken)]) == 2
    err = capsys.readouterr().err  # line and column, the line once
    assert err.startswith(f"{broken}:4:") and err.endswith(": malformed XML: mismatched tag\n")
    assert err.count(":4") == 1


def structure(path: Path) -> list[tuple[str, str, str, dict[str, str]]]:
    tree = load_tree(str(path))
    return [(w.path, w.node_id, w.name,
             {k: str(v) for k, v in getattr(w.node, "bindings", {}).items()})
            for w in walk_nodes(tree.root)]


HUMBLE_TREES = sorted(p for p in HUMBLE.glob("*.xml") if p.name != "nav2_tree_nodes.xml") \
    if HUMBLE.is_dir() else []


@pytest.mark.skipif(not HUMBLE_TREES, reason=f"Humble's Nav2 trees are not in {HUMBLE}")
@pytest.mark.parametrize("path", HUMBLE_TREES, ids=lambda p: p.stem)
def test_humble_trees_converted_load_as_the_originals(path: Path, tmp_path: Path) -> None:
    dest = tmp_path / path.name
    assert run_convert(str(path), "-o", str(dest)) == 0
    converted = structure(dest)
    assert converted == structure(path)
    assert len(converted) > 1
