"""bench --backend ray: the same episodes on a local Ray cluster (2 CPUs) as in worker
processes, seed for seed."""

from __future__ import annotations

import json
import shutil
from pathlib import Path
from typing import Any

import pytest

from bt_manip.cli import main

pytest.importorskip("ray")

ROOT = Path(__file__).resolve().parents[2]
TREE = """<root BTCPP_format="4"><BehaviorTree ID="Main"><Sequence>
  <MoveJoints state="home"/>
  <Script code="n := 7"/>
  <AlwaysSuccess name="step"/>
</Sequence></BehaviorTree></root>"""


def _outcomes(folder: Path) -> list[tuple[Any, ...]]:
    episodes = json.loads((folder / "episodes.json").read_text())["episodes"]
    return [(e["seed"], e["status"], e["reason"], e["sim_time"], e["ticks"], e["metrics"],
             e["injected"]) for e in episodes]


def test_ray_backend_gives_the_process_pools_results_seed_for_seed(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    # a folder of its own, as a user's project: the tree, the world and its robots
    (tmp_path / "worlds").mkdir()
    shutil.copy(ROOT / "worlds" / "sawyer_table.yaml", tmp_path / "worlds")
    shutil.copytree(ROOT / "robots", tmp_path / "robots")
    (tmp_path / "tree.xml").write_text(TREE)
    monkeypatch.chdir(tmp_path)
    common = ["bench", "tree.xml", "--world", "worlds/sawyer_table.yaml", "--runs", "4",
              "--jobs", "2", "--inject", "step:failure:0.6"]
    assert main([*common, "--out", "pool"]) == 1
    assert main([*common, "--out", "ray", "--backend", "ray"]) == 1
    pool, ray = _outcomes(tmp_path / "pool"), _outcomes(tmp_path / "ray")
    assert [o[0] for o in ray] == [0, 1, 2, 3]
    assert {o[1] for o in ray} == {"SUCCESS", "FAILURE"}
    assert ray == pool
    # and the same tree coverage, to the byte
    coverage = (tmp_path / "pool" / "coverage.json").read_text()
    assert (tmp_path / "ray" / "coverage.json").read_text() == coverage
    assert json.loads(coverage)["node_coverage"]["ticked"] == 4


def test_ray_backend_refuses_files_outside_the_folder_it_ships(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
        capsys: pytest.CaptureFixture[str]) -> None:
    (tmp_path / "tree.xml").write_text(TREE)
    inside = tmp_path / "project"
    inside.mkdir()
    monkeypatch.chdir(inside)
    code = main(["bench", str(tmp_path / "tree.xml"), "--world",
                 str(ROOT / "worlds" / "sawyer_table.yaml"), "--runs", "1", "--out", "o",
                 "--backend", "ray"])
    assert code == 2
    assert "outside" in capsys.readouterr().err
