"""bench's tree coverage: which branches and recoveries the episodes ran, the same with one
process or two, after a resume, and summed over a sweep; coverage.json follows its schema."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest

from bt_manip.bench.coverage import COVERAGE_NAME
from bt_manip.bench.log import LOG_NAME
from bt_manip.cli import main
from tests.bench.interrupts import interrupted_when

ROOT = Path(__file__).resolve().parents[2]
WORLD = str(ROOT / "worlds" / "sawyer_table.yaml")
SCHEMAS = ROOT / "docs" / "schemas"
TREE = """<root BTCPP_format="4">
  <BehaviorTree ID="Main">
    <Sequence name="main">
      <Sleep msec="100"/>
      <Fallback name="try_or_recover">
        <AlwaysSuccess name="step"/>
        <Sequence name="recover">
          <Script name="note" code="recovered := 1"/>
          <AlwaysSuccess name="recovered_ok"/>
        </Sequence>
        <AlwaysFailure name="give_up"/>
      </Fallback>
      <IfThenElse name="choose">
        <ScriptCondition code="true"/>
        <AlwaysSuccess name="then_branch"/>
        <AlwaysSuccess name="else_branch"/>
      </IfThenElse>
    </Sequence>
  </BehaviorTree>
</root>
"""
RECOVER = "main/try_or_recover/recover"


def _bench(tree: Path, out: Path, *extra: str, jobs: str = "1") -> int:
    """Six seeds; the step fails in some of them (the fault is drawn per seed), so the
    recovery runs in some episodes only."""
    return main(["bench", str(tree), "--world", WORLD, "--runs", "6", "--jobs", jobs,
                 "--inject", "step:failure:0.7", "--out", str(out), *extra])


@pytest.fixture(scope="module")
def benched(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A folder with the tree and the bench of it with one process (``one``)."""
    folder = tmp_path_factory.mktemp("coverage")
    (folder / "tree.xml").write_text(TREE)
    assert _bench(folder / "tree.xml", folder / "one") == 0
    return folder


def _coverage(folder: Path) -> dict[str, Any]:
    return dict(json.loads((folder / COVERAGE_NAME).read_text()))


def _branch(data: dict[str, Any], path: str) -> dict[str, Any]:
    return next(br for bn in data["branch_nodes"] for br in bn["branches"] if br["path"] == path)


def test_coverage_shows_the_recovery_that_ran_under_faults_and_names_those_that_never_did(
        benched: Path) -> None:
    data = _coverage(benched / "one")
    failed = sum(1 for e in json.loads((benched / "one" / "episodes.json").read_text())
                 ["episodes"] if e["injected"])
    assert 0 < failed < 6
    recover = _branch(data, RECOVER)
    assert recover["episodes"] == recover["won"] == failed and recover["recovery"]
    assert _branch(data, "main/try_or_recover/step")["won"] == 6 - failed
    never = [(r["path"], r["line"], r["role"]) for r in data["recoveries"]["never_exercised"]]
    assert never == [("main/try_or_recover/give_up", 11, "recovery"),
                     ("main/choose/else_branch", 16, "else")]
    assert data["branch_coverage"] == {"covered": 3, "total": 5, "ratio": 0.6}
    assert data["recoveries"]["exercised"] == 1 and data["recoveries"]["total"] == 3
    nodes = {n["path"]: n for n in data["nodes"]}
    assert nodes["main/try_or_recover/step"]["failure"] == failed
    assert nodes["main/try_or_recover/give_up"]["episodes"] == 0
    assert nodes["main/try_or_recover/give_up"]["line"] == 11
    assert (benched / "one" / "coverage.png").stat().st_size > 0


def test_one_process_and_two_give_the_same_coverage(benched: Path,
                                                    capsys: pytest.CaptureFixture[str]) -> None:
    capsys.readouterr()
    assert _bench(benched / "tree.xml", benched / "two", jobs="2") == 0
    out = capsys.readouterr().out
    assert "coverage: 3/5 branches ran (60.0 %)" in out
    assert "main/choose/else_branch [AlwaysSuccess]" in out and "tree.xml:16" in out
    one = (benched / "one" / COVERAGE_NAME).read_text()
    assert (benched / "two" / COVERAGE_NAME).read_text() == one


def test_a_resumed_bench_has_the_coverage_of_an_uninterrupted_one(
        benched: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    with interrupted_when(monkeypatch, lambda spec: spec.seed == 3):
        assert _bench(benched / "tree.xml", benched / "cut") == 130
    assert not (benched / "cut" / COVERAGE_NAME).exists()
    assert main(["bench", "--resume", str(benched / "cut"), "--jobs", "2"]) == 0
    assert ((benched / "cut" / COVERAGE_NAME).read_text()
            == (benched / "one" / COVERAGE_NAME).read_text())


def test_a_sweep_sums_the_coverage_of_its_values(tmp_path: Path) -> None:
    (tmp_path / "tree.xml").write_text(TREE)
    assert main(["bench", str(tmp_path / "tree.xml"), "--world", WORLD, "--runs", "2",
                 "--jobs", "1", "--sweep", "step:failure:{0,1}", "--out",
                 str(tmp_path / "s")]) == 0
    never, always = (_coverage(tmp_path / "s" / sub) for sub in ("00_0", "01_1"))
    assert _branch(never, RECOVER)["episodes"] == 0
    assert _branch(always, RECOVER)["episodes"] == 2
    merged = _coverage(tmp_path / "s")
    assert merged["sweep"] == "step:failure:{0,1}" and merged["runs"] == 4
    assert merged["seeds"] == [0, 0, 1, 1]
    assert _branch(merged, RECOVER)["episodes"] == 2
    assert merged["branch_coverage"]["covered"] == 3
    jsonschema = pytest.importorskip("jsonschema")
    schema = json.loads((SCHEMAS / "bench-coverage.schema.json").read_text())
    for data in (never, always, merged):
        jsonschema.Draft202012Validator(schema).validate(data)


def test_resume_refuses_a_bench_of_the_previous_format(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    (tmp_path / "old").mkdir()
    header = {"kind": "bench", "schema_version": 2, "seeds": [0, 1],
              "spec": {"tree": "t.xml", "world": None}, "digests": {}}
    (tmp_path / "old" / LOG_NAME).write_text(json.dumps(header) + "\n")
    assert main(["bench", "--resume", str(tmp_path / "old")]) == 2
    err = capsys.readouterr().err
    assert "older bt-manip (format version 2" in err and "start a new bench" in err
