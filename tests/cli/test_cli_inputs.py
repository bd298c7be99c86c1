"""Command-line inputs: output paths checked before a run, ``--import`` of the user's node
modules, the cause of a failed run, included directories. Exact messages and exit codes."""

from __future__ import annotations

import json
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest
from tree_files import write_tree

from bt_manip.bt import registry
from bt_manip.cli import main

ROOT = Path(__file__).resolve().parents[2]
TABLE = ROOT / "worlds" / "sawyer_table.yaml"

NODE_MODULE = '''\
"""A node for the tests: fails at once with a reason."""
from py_trees.common import Status

from bt_manip.bt import ActionNode, registry


@registry.register
class RefuseForTest(ActionNode):
    """FAILURE at once, saying so."""

    def update(self) -> Status:
        self.feedback_message = "refused on purpose"
        return Status.FAILURE
'''


@pytest.fixture
def node_module(tmp_path: Path) -> Iterator[Path]:
    """``refuse_nodes.py`` in tmp_path; the node it registers is unregistered afterwards."""
    path = tmp_path / "refuse_nodes.py"
    path.write_text(NODE_MODULE)
    yield path
    registry.unregister("RefuseForTest")
    for name in [m for m in sys.modules if m.startswith(("bt_manip_user_", "refuse_nodes"))]:
        del sys.modules[name]


# -- output paths ------------------------------------------------------------------------------


def test_report_pointing_at_a_directory_is_refused_before_the_run(tmp_path: Path) -> None:
    tree = write_tree(tmp_path, '<Sleep msec="100"/>')
    proc = subprocess.run(
        [sys.executable, "-m", "bt_manip.cli", "run", str(tree), "--report", str(tmp_path)],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert proc.returncode == 2
    assert proc.stderr == (
        f"--report: {tmp_path} is a directory; give a file path, e.g. {tmp_path}/report.json\n"
    )
    assert proc.stdout == ""  # the run did not start


def test_every_output_flag_is_checked(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    tree = write_tree(tmp_path, "<AlwaysSuccess/>")
    a_file = tmp_path / "a_file"
    a_file.write_text("")
    missing = tmp_path / "missing"
    cases = [
        (["run", str(tree), "--bb-out", str(tmp_path)],
         f"--bb-out: {tmp_path} is a directory; give a file path, e.g. {tmp_path}/blackboard.json"),
        (["run", str(tree), "--report", str(a_file / "r.json")],
         f"--report: {a_file} is not a folder, so r.json cannot be written in it"),
        (["run", str(tree), "--record", str(missing / "deeper" / "r.html")],
         f"--record: the folder {missing} does not exist (bt-manip creates at most the "
         f"output's own folder, deeper); create {missing} first or choose another path"),
        (["bench", str(tree), "--world", str(TABLE), "--out", str(a_file)],
         f"--out: {a_file} is a file, not a folder; give a folder for the outputs"),
        (["bench", str(tree), "--world", str(TABLE), "--out", str(missing / "bench")],
         f"--out: the folder {missing} does not exist (bt-manip creates at most the "
         f"output's own folder, bench); create {missing} first or choose another path"),
        (["show", str(tree), "--dot", str(tmp_path)],
         f"--dot: {tmp_path} is a directory; give a file path, e.g. {tmp_path}/tree.dot"),
    ]
    for argv, message in cases:
        assert main(argv) == 2, argv
        captured = capsys.readouterr()
        assert captured.err == message + "\n", argv
        assert captured.out == "", argv
    assert not missing.exists()


def test_bench_default_output_folder_under_a_file_named_out(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.chdir(tmp_path)
    (tmp_path / "out").write_text("")
    tree = write_tree(tmp_path, "<AlwaysSuccess/>")
    assert main(["bench", str(tree), "--world", str(TABLE)]) == 2
    assert capsys.readouterr().err == (
        "--out: out is not a folder, so the outputs cannot be written below it\n"
    )


def test_outputs_create_their_own_folder_only(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    tree = write_tree(tmp_path, '<Script code="x := 2"/>')
    report, bb = tmp_path / "new" / "r.json", tmp_path / "new2" / "bb.json"
    assert main(["run", str(tree), "--quiet", "--report", str(report), "--bb-out", str(bb)]) == 0
    assert json.loads(report.read_text())["status"] == "SUCCESS"
    assert json.loads(bb.read_text()) == {"x": 2}


# -- --import ----------------------------------------------------------------------------------


def test_import_by_file_registers_nodes_for_run_and_validate(
    tmp_path: Path, node_module: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    tree = write_tree(tmp_path, '<RefuseForTest name="no"/>')
    assert main(["validate", str(tree)]) == 2
    assert "unknown node 'RefuseForTest'" in capsys.readouterr().err
    assert main(["validate", str(tree), "--import", str(node_module)]) == 0
    assert capsys.readouterr().out == f"{tree}: OK\n"
    assert main(["run", str(tree), "--quiet", "--import", str(node_module)]) == 1
    assert "result: FAILURE (no: refused on purpose)" in capsys.readouterr().out


def test_import_by_module_name_looks_in_the_working_directory(
    tmp_path: Path, node_module: Path, monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(sys, "path", [p for p in sys.path if p not in ("", str(tmp_path))])
    tree = write_tree(tmp_path, "<RefuseForTest/>")
    assert main(["show", str(tree), "--import", "refuse_nodes"]) == 0
    assert "RefuseForTest" in capsys.readouterr().out


def test_import_problems_name_the_flag(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(sys, "path", list(sys.path))  # --import puts the working dir on it
    tree = write_tree(tmp_path, "<AlwaysSuccess/>")
    (tmp_path / "broken.py").write_text("x = 1\ndef f(:\n")
    (tmp_path / "raising.py").write_text("import math\n\nraise RuntimeError('no robot here')\n")
    (tmp_path / "adir").mkdir()
    cases = [
        ("", "--import: needs a module name or a .py file, got ''"),
        ("no_such_module", f"--import: no module named 'no_such_module' (looked in {tmp_path} "
                           "and the installed packages); give a module name or a .py file"),
        ("missing.py", "--import: missing.py not found; give a Python file (.py) or a module "
                       "name"),
        ("./adir", "--import: adir is a directory; give a Python file (.py) or a module name"),
        ("broken.py", f"--import: {tmp_path / 'broken.py'}:2: syntax error in module "
                      "'broken.py': invalid syntax"),
        ("raising", f"--import: {tmp_path / 'raising.py'}:3: importing 'raising' raised "
                    "RuntimeError: no robot here"),
    ]
    for verb in (["run", str(tree)], ["validate", str(tree)], ["nodes"]):
        for module, message in cases:
            assert main([*verb, "--import", module]) == 2, (verb, module)
            assert capsys.readouterr().err == message + "\n", (verb, module)


def test_model_only_node_hint_names_the_import_flag(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    tree = tmp_path / "m.xml"
    tree.write_text(
        '<root BTCPP_format="4">\n'
        '  <BehaviorTree ID="Main"><Grab/></BehaviorTree>\n'
        '  <TreeNodesModel><Action ID="Grab"/></TreeNodesModel>\n'
        "</root>\n"
    )
    assert main(["run", str(tree)]) == 2
    assert capsys.readouterr().err == (
        f"{tree}:2: node 'Grab' is declared in a TreeNodesModel but has no implementation; "
        "import the Python module that registers it with --import MODULE\n"
    )


def test_include_of_a_directory_says_so(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    (tmp_path / "adir").mkdir()
    tree = tmp_path / "inc.xml"
    tree.write_text(
        '<root BTCPP_format="4" main_tree_to_execute="Main">\n'
        '  <include path="adir"/>\n'
        '  <BehaviorTree ID="Main"><AlwaysSuccess/></BehaviorTree>\n'
        "</root>\n"
    )
    assert main(["validate", str(tree)]) == 2
    assert capsys.readouterr().err == (
        f"{tree}:2: included path 'adir' is a directory ({tmp_path / 'adir'}); include an XML "
        'file, e.g. <include path="subtrees.xml"/>\n'
    )


# -- the cause of a failed run -----------------------------------------------------------------

IGNORED_THEN_REAL = """\
    <Sequence>
      <ForceSuccess><Sequence><Sequence><RefuseForTest name="ignored"/></Sequence></Sequence>
      </ForceSuccess>
      <Fallback>
        <RefuseForTest name="plan_a"/>
        <RetryUntilSuccessful num_attempts="2">
          <Sequence name="attempt"><AlwaysSuccess/><RefuseForTest name="real"/></Sequence>
        </RetryUntilSuccessful>
      </Fallback>
    </Sequence>"""


def test_cause_is_the_failure_that_ended_the_run_not_one_the_tree_ignored(
    tmp_path: Path, node_module: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    tree = write_tree(tmp_path, IGNORED_THEN_REAL)
    report = tmp_path / "r.json"
    code = main(["run", str(tree), "--quiet", "--import", str(node_module),
                 "--report", str(report)])
    assert code == 1
    real = "Sequence/Fallback/RetryUntilSuccessful/attempt/real"
    data = json.loads(report.read_text())
    assert data["reason"] == f"{real}: refused on purpose"
    assert data["cause"] == {"path": real, "name": "real", "node": "RefuseForTest",
                             "reason": "refused on purpose"}
    lines = capsys.readouterr().out.splitlines()
    assert lines[0] == f"result: FAILURE ({real}: refused on purpose)"
    assert lines[2] == f"  FAILURE {real} [RefuseForTest]: refused on purpose (ended the run)"


def test_cause_of_a_built_in_failure_without_a_reason(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    tree = write_tree(
        tmp_path,
        '<Sequence><ForceSuccess><AlwaysFailure name="tolerated"/></ForceSuccess>'
        '<Inverter name="must_not_hold"><AlwaysSuccess/></Inverter></Sequence>',
    )
    assert main(["run", str(tree), "--quiet"]) == 1
    assert capsys.readouterr().out.splitlines()[0] == (
        "result: FAILURE (Sequence/must_not_hold: Inverter returned FAILURE because "
        "AlwaysSuccess 'AlwaysSuccess' succeeded)"
    )


def test_bench_counts_failures_by_the_node_that_failed(
    tmp_path: Path, node_module: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    tree = write_tree(tmp_path, IGNORED_THEN_REAL)
    out = tmp_path / "bench"
    code = main(["bench", str(tree), "--world", str(TABLE), "--runs", "2", "--jobs", "2",
                 "--import", str(node_module), "--out", str(out)])
    assert code == 1
    summary = json.loads((out / "summary.json").read_text())
    real = "Sequence/Fallback/RetryUntilSuccessful/attempt/real"
    assert summary["failures"] == [
        {"node": "real (RefuseForTest)", "reason": f"{real}: refused on purpose", "count": 2}
    ]
    assert f"  2 x real (RefuseForTest): {real}: refused on purpose" in capsys.readouterr().out


@pytest.mark.parametrize(
    ("body", "cause"),
    [
        # a recovery branch that passes the failure on: the cause is what failed in the try
        ('<Fallback name="grasp_or_back_off">'
         '<Sequence name="try"><AlwaysSuccess/><RefuseForTest name="grasp"/></Sequence>'
         '<Sequence name="back_off"><AlwaysSuccess name="release"/>'
         '<AlwaysFailure name="grasp_failed"/></Sequence></Fallback>',
         "grasp_or_back_off/try/grasp: refused on purpose"),
        # a failure left over from an earlier attempt is not the cause of the last one
        ('<Sequence><Script code="n := 0"/><RetryUntilSuccessful num_attempts="2">'
         '<Sequence name="attempt"><Script code="n := n + 1"/>'
         '<AlwaysFailure name="gives_up" _skipIf="n == 1"/><RefuseForTest name="stale"/>'
         "</Sequence></RetryUntilSuccessful></Sequence>",
         "Sequence/RetryUntilSuccessful/attempt/gives_up: AlwaysFailure returned FAILURE"),
    ],
)
def test_cause_follows_the_failures_of_the_last_run(
    tmp_path: Path, node_module: Path, capsys: pytest.CaptureFixture[str], body: str, cause: str
) -> None:
    tree = write_tree(tmp_path, body)
    assert main(["run", str(tree), "--quiet", "--import", str(node_module)]) == 1
    assert capsys.readouterr().out.splitlines()[0] == f"result: FAILURE ({cause})"
