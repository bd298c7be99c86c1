"""Malformed world files: each exits 2 with one line naming the file, line and problem."""

from __future__ import annotations

from pathlib import Path

import pytest

from bt_manip.cli import main

BAD = Path(__file__).parent / "bad_worlds"

CASES = [
    ("bad_yaml.yaml", 4, "invalid YAML"),
    ("unknown_key.yaml", 6, "unknown key 'colr' in furniture[0]; did you mean 'color'?"),
    ("missing_mesh.yaml", 4, "mesh not found: meshes/statue.stl"),
    ("negative_mass.yaml", 6, "objects[0].mass must be > 0, got -1.0"),
    ("overlap.yaml", 4, "'crate_a' and 'crate_b' overlap by 200 mm at spawn"),
    ("unknown_robot.yaml", 4, "unknown robot 'r2d2'"),
    ("missing_urdf.yaml", 4, "file not found: assets/no_such_shelf.urdf"),
    ("door_too_wide.yaml", 7, "does not fit in the wall of length 2.000 m"),
    ("bad_pose.yaml", 3, "poses.goal ([x, y, yaw]) must be a list of 3 numbers"),
    ("duplicate_name.yaml", 4, "name 'box_1' is used twice (first at line 3)"),
    ("bad_colour.yaml", 3, "unknown colour 'chartreuse'"),
    ("not_a_mapping.yaml", 1, "a world file must be a YAML mapping"),
    ("zero_size.yaml", 3, "objects[0].size must be positive"),
]


@pytest.mark.parametrize(("name", "line", "text"), CASES, ids=[c[0] for c in CASES])
def test_bad_world_exits_2_with_one_line(
    name: str, line: int, text: str, capsys: pytest.CaptureFixture[str]
) -> None:
    path = BAD / name
    code = main(["world", str(path)])
    out, err = capsys.readouterr()
    assert code == 2
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith(f"{path}:{line}: "), lines[0]
    assert text in lines[0]
    assert "Traceback" not in out + err


def test_every_problem_is_reported_in_one_run(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    world = tmp_path / "many.yaml"
    world.write_text(
        "name: many\n"
        "furnitur: []\n"
        "objects:\n"
        "  - {name: a, shape: box, size: [0.1, 0.1, 0.1], mass: 0, pose: [0, 0, 0]}\n"
        "  - {name: b, shape: cone, size: [0.1, 0.1, 0.1], mass: 1, pose: [1, 0, 0]}\n"
        "poses:\n"
        "  p: {x: 1, y: 2, yaw: 0.5, qz: 0.1}\n"
    )
    assert main(["world", str(world)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert [e.split(": ", 1)[0] for e in err] == [
        f"{world}:2",
        f"{world}:4",
        f"{world}:5",
        f"{world}:7",
    ]
