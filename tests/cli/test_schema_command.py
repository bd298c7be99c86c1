"""``bt-manip schema``: the JSON Schemas of the output files, listed and printed from the folder
bt-manip has them in (docs/schemas in a clone; an installed wheel's copy: tests/test_wheel.py)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from bt_manip.cli import main

SCHEMAS = Path(__file__).resolve().parents[2] / "docs" / "schemas"


def test_schema_prints_the_run_reports_json_schema(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["schema", "run-report"]) == 0
    printed = json.loads(capsys.readouterr().out)
    assert printed == json.loads((SCHEMAS / "run-report.schema.json").read_text())
    assert printed["$id"] == "urn:bt-manip:schema:run-report"


def test_schema_lists_every_schema_with_its_file(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["schema"]) == 0
    out = capsys.readouterr().out
    for path in SCHEMAS.glob("*.schema.json"):
        name = path.name.removesuffix(".schema.json")
        assert f"{name} " in out and str(path.resolve()) in out
    assert "bt-manip bench: summary.json" in out  # each schema's title
    assert main(["schema", "bench-summary", "--path"]) == 0
    printed = Path(capsys.readouterr().out.strip())
    assert printed == (SCHEMAS / "bench-summary.schema.json").resolve()


def test_an_unknown_schema_is_bad_input_naming_the_known_ones(
        capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["schema", "run_report"]) == 2
    err = capsys.readouterr().err
    assert "schema: no schema named 'run_report'; known: bench-coverage, bench-episode," in err
    assert "run-report" in err and "Traceback" not in err
