"""``bt-manip coverage``: the summary of a bench's coverage.json, --min for CI, --diff."""

from __future__ import annotations

from pathlib import Path

import pytest

from bt_manip.cli import main

ROOT = Path(__file__).resolve().parents[2]
WORLD = str(ROOT / "worlds" / "sawyer_table.yaml")
TREE = """<root BTCPP_format="4"><BehaviorTree ID="Main">
  <Fallback name="try_or_recover">
    <AlwaysSuccess name="step"/>
    <AlwaysSuccess name="recover"/>
  </Fallback>
</BehaviorTree></root>
"""


@pytest.fixture(scope="module")
def benches(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """``clean``: the step never fails (its recovery never runs); ``faulty``: it always does."""
    folder = tmp_path_factory.mktemp("benches")
    (folder / "tree.xml").write_text(TREE)
    for out, p in (("clean", "0"), ("faulty", "1")):
        assert main(["bench", str(folder / "tree.xml"), "--world", WORLD, "--runs", "2",
                     "--jobs", "1", "--inject", f"step:failure:{p}",
                     "--out", str(folder / out)]) == 0
    return folder


def test_coverage_prints_the_summary_and_min_gives_the_exit_code(
        benches: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["coverage", str(benches / "clean")]) == 0
    out = capsys.readouterr().out
    assert "coverage: 1/2 branches ran (50.0 %)" in out
    assert "try_or_recover/recover [AlwaysSuccess]" in out and "tree.xml:4" in out
    assert main(["coverage", str(benches / "clean"), "--min", "0.8"]) == 1
    assert "branch coverage 50.0 % is under --min 80 %" in capsys.readouterr().out
    assert main(["coverage", str(benches / "clean"), "--min", "0.5"]) == 0
    capsys.readouterr()
    assert main(["coverage", str(benches / "faulty"), "--min", "1"]) == 0
    out = capsys.readouterr().out
    assert "2/2 branches ran (100.0 %)" in out and "never exercised" not in out


def test_coverage_all_lists_every_branch(benches: Path,
                                         capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["coverage", str(benches / "faulty"), "--all"]) == 0
    out = capsys.readouterr().out
    assert "try_or_recover [Fallback]" in out
    assert "   2 ran    0 won  first     step [AlwaysSuccess]" in out
    assert "   2 ran    2 won  recovery  recover [AlwaysSuccess]" in out


def test_coverage_diff_names_the_branches_that_ran_in_one_bench_only(
        benches: Path, capsys: pytest.CaptureFixture[str]) -> None:
    clean, faulty = str(benches / "clean"), str(benches / "faulty")
    assert main(["coverage", faulty, "--diff", clean]) == 0
    out = capsys.readouterr().out
    assert f"branch coverage: 1/2 (50.0 %, 2 episodes) in {clean} -> 2/2 (100.0 %" in out
    assert f"ran in {faulty} only (1):\n  try_or_recover/recover [recovery]" in out
    assert main(["coverage", clean, "--diff", clean]) == 0
    assert "the same branches ran in the same number of episodes" in capsys.readouterr().out


def test_coverage_of_a_folder_without_one_is_bad_input(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["coverage", str(tmp_path)]) == 2
    assert "no coverage.json here" in capsys.readouterr().err
    (tmp_path / "coverage.json").write_text("{")
    assert main(["coverage", str(tmp_path)]) == 2
    assert "not a bench's coverage.json" in capsys.readouterr().err
    with pytest.raises(SystemExit) as exc:
        main(["coverage", str(tmp_path), "--min", "80"])
    assert exc.value.code == 2
