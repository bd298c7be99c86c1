"""The run report (`run --report`) carries schema_version and follows
docs/schemas/run-report.schema.json."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest
from tree_files import write_tree

from bt_manip.cli import main
from bt_manip.run.report import REPORT_SCHEMA_VERSION

ROOT = Path(__file__).resolve().parents[2]
SCHEMA = ROOT / "docs" / "schemas" / "run-report.schema.json"
WORLD = str(ROOT / "worlds" / "sawyer_table.yaml")

jsonschema = pytest.importorskip("jsonschema")


def _validator() -> Any:
    return jsonschema.Draft202012Validator(json.loads(SCHEMA.read_text()))


def _report(tmp_path: Path, name: str, argv: list[str]) -> dict[str, Any]:
    out = tmp_path / f"{name}.json"
    main([*argv, "--quiet", "--report", str(out)])
    return dict(json.loads(out.read_text()))


def test_reports_of_every_kind_of_run_follow_the_schema(tmp_path: Path) -> None:
    validator = _validator()
    plain = _report(tmp_path, "plain", ["run", str(ROOT / "trees" / "builtins_demo.xml")])
    failed = write_tree(tmp_path, '<Sequence><OpenGripper name="open"/>'
                        '<Sleep msec="100"/></Sequence>', "failed.xml")
    faulty = _report(tmp_path, "faulty", ["run", str(failed), "--world", WORLD,
                                          "--inject", "open:failure:1"])
    budget = write_tree(tmp_path, '<Sleep msec="100000"/>', "budget.xml")
    spent = _report(tmp_path, "spent", ["run", str(budget), "--max-ticks", "2"])
    for report in (plain, faulty, spent):
        validator.validate(report)
        assert report["schema_version"] == REPORT_SCHEMA_VERSION == 1
    assert plain["status"] == "SUCCESS" and plain["seed"] is None and plain["cause"] == {}
    assert faulty["status"] == "FAILURE" and faulty["seed"] == 0
    assert faulty["cause"]["name"] == "open" and faulty["cause"]["node"] == "OpenGripper"
    assert faulty["extra"]["inject"] == ["open:failure:1"]
    assert [e["target"] for e in faulty["extra"]["injected"]] == ["open"]
    assert spent["status"] == "BUDGET" and spent["exit_code"] == 1


def test_the_schema_refuses_a_report_without_its_version_or_with_unknown_fields(
        tmp_path: Path) -> None:
    validator = _validator()
    report = _report(tmp_path, "plain", ["run", str(ROOT / "trees" / "builtins_demo.xml")])
    unversioned = {k: v for k, v in report.items() if k != "schema_version"}
    with pytest.raises(jsonschema.ValidationError, match="schema_version"):
        validator.validate(unversioned)
    with pytest.raises(jsonschema.ValidationError, match="surprise"):
        validator.validate({**report, "surprise": 1})
    with pytest.raises(jsonschema.ValidationError):
        validator.validate({**report, "schema_version": 2})
    bad_node = {**report, "nodes": [{**report["nodes"][0], "status": "DONE"}]}
    with pytest.raises(jsonschema.ValidationError, match="DONE"):
        validator.validate(bad_node)
