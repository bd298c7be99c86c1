"""``bt-manip motion-bench``: a tiny MotionBenchMaker family written here, the figures printed,
the results file against its JSON Schema, and bad input (exit 2 with file and line)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from bt_manip.cli import main
from tests.manipulation.mbm_family import LEFT, RIGHT, SRDF, URDF, write_family

SCHEMAS = Path(__file__).resolve().parents[2] / "docs" / "schemas"


def test_motion_bench_prints_figures_and_writes_results(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    jsonschema = pytest.importorskip("jsonschema")
    write_family(tmp_path / "problems" / "wall_panda")
    out = tmp_path / "results.json"
    code = main(["motion-bench", str(tmp_path / "problems"), "--urdf", str(URDF),
                 "--srdf", str(SRDF), "--time-limit", "30", "--seed", "3", "--out", str(out)])
    printed = capsys.readouterr().out
    assert code == 0
    assert "wall_panda" in printed and "overall" in printed and "median ms" in printed
    document = json.loads(out.read_text())
    jsonschema.validate(document, json.loads((SCHEMAS / "motion-bench.schema.json").read_text()))
    assert document["robot"] == "panda" and document["planner"] == "rrtconnect"
    assert document["seed"] == 3 and document["time_limit_s"] == 30.0
    assert document["collision_step_rad"] == 0.05
    (problem,) = document["problems"]
    assert (problem["family"], problem["scene"], problem["request"]) == (
        "wall_panda", "scene0001.yaml", "request0001.yaml")
    assert problem["solved"] and problem["valid"] and problem["planning_ms"] > 0
    assert problem["joint_names"] == [f"panda_joint{i}" for i in range(1, 8)]
    assert np.allclose(problem["path"][0], LEFT) and np.allclose(problem["path"][-1], RIGHT)
    assert problem["path_length_rad"] >= float(np.linalg.norm(np.subtract(RIGHT, LEFT)))


def test_motion_bench_without_srdf_plans_the_goals_joints(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    folder = write_family(tmp_path / "wall_panda")
    out = tmp_path / "results.json"
    assert main(["motion-bench", str(folder), "--urdf", str(URDF), "--out", str(out)]) == 0
    (problem,) = json.loads(out.read_text())["problems"]
    assert problem["joint_names"] == [f"panda_joint{i}" for i in range(1, 8)]


def test_a_broken_scene_is_bad_input_naming_its_file_and_line(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    folder = write_family(tmp_path / "wall_panda")
    scene = folder / "scene0001.yaml"
    scene.write_text(scene.read_text().replace("[0.3, 0.05, 0.9]", "[0.3, 0.05]"))
    code = main(["motion-bench", str(folder), "--urdf", str(URDF), "--srdf", str(SRDF)])
    err = capsys.readouterr().err
    assert code == 2
    assert f"{scene}:" in err and "primitive type 'box' with 2 dimensions" in err
    line = err.split(f"{scene}:", 1)[1].split(":", 1)[0]
    assert line.isdigit()


def test_a_missing_folder_or_group_is_bad_input(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["motion-bench", str(tmp_path / "nothing"), "--urdf", str(URDF)]) == 2
    assert "no such folder" in capsys.readouterr().err
    folder = write_family(tmp_path / "wall_panda")
    assert main(["motion-bench", str(folder), "--urdf", str(URDF), "--srdf", str(SRDF),
                 "--group", "legs"]) == 2
    assert "no group 'legs'" in capsys.readouterr().err
