"""World files' ``schema_version``: 1 (or none) is read, anything else is refused at its line
before any other check."""

from __future__ import annotations

from pathlib import Path

import pytest

from bt_manip.cli import main
from bt_manip.sim.world_reader import parse_world
from bt_manip.sim.world_spec import WORLD_SCHEMA_VERSION

ROOM = """\
name: versioned
walls:
  - {from: [0, 0], to: [2, 0]}
objects:
  - {name: crate, shape: box, size: [0.2, 0.2, 0.2], mass: 1.0, pose: [1.0, 1.0, 0.0]}
"""


def _world(tmp_path: Path, head: str, body: str = ROOM) -> Path:
    path = tmp_path / "w.yaml"
    path.write_text(head + body)
    return path


@pytest.mark.parametrize("head", ["", "schema_version: 1\n"], ids=["absent", "one"])
def test_version_one_or_none_is_read(tmp_path: Path, head: str) -> None:
    spec = parse_world(_world(tmp_path, head))
    assert WORLD_SCHEMA_VERSION == 1
    assert spec.name == "versioned" and [o.name for o in spec.objects] == ["crate"]


def test_a_newer_version_is_refused_alone_at_its_line(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    # a world of a future format: its new keys are not reported one by one
    path = _world(tmp_path, "# from a later release\nschema_version: 2\nlighting: {sun: true}\n")
    assert main(["world", str(path)]) == 2
    out, err = capsys.readouterr()
    lines = err.strip().splitlines()
    assert lines == [
        f"{path}:2: schema_version 2 is newer than the world format this bt-manip reads "
        "(version 1); upgrade bt-manip to load this world"
    ]
    assert "Traceback" not in out + err


@pytest.mark.parametrize("value", ["0", "-1", "1.5", "'1'", "true", "[1]"])
def test_a_version_that_is_no_whole_number_from_1_is_refused(
        tmp_path: Path, value: str, capsys: pytest.CaptureFixture[str]) -> None:
    path = _world(tmp_path, f"schema_version: {value}\n")
    assert main(["world", str(path)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith(f"{path}:1: schema_version must be a whole number >= 1, got ")
    assert err.endswith("(this bt-manip reads version 1)")


def test_the_run_verb_refuses_a_newer_world_too(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    world = _world(tmp_path, "schema_version: 7\n")
    tree = Path(__file__).resolve().parents[2] / "trees" / "builtins_demo.xml"
    assert main(["run", str(tree), "--world", str(world)]) == 2
    assert f"{world}:1: schema_version 7 is newer" in capsys.readouterr().err
