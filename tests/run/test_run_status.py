"""RunStatus travels as its value: the console summary line and the report's JSON show
``SUCCESS``, never ``RunStatus.SUCCESS``; each status has its exit code."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from bt_manip.run.report import RunReport
from bt_manip.run.status import EXIT_CODES, RunStatus

EXPECTED_CODES = {"SUCCESS": 0, "FAILURE": 1, "SKIPPED": 1, "BUDGET": 1, "ERROR": 2,
                  "INTERRUPTED": 130}


def test_every_status_and_its_exit_code() -> None:
    assert {s.value: s.exit_code for s in RunStatus} == EXPECTED_CODES
    assert {str(s): code for s, code in EXIT_CODES.items()} == EXPECTED_CODES


@pytest.mark.parametrize("status", list(RunStatus))
def test_the_summary_line_and_the_json_show_the_value(status: RunStatus,
                                                      tmp_path: Path) -> None:
    report = RunReport(status=status, reason="why", sim_time=1.5, wall_time=0.5, ticks=30)
    assert report.summary().splitlines()[0] == f"result: {status.value} (why)"
    assert str(status) == f"{status}" == f"{status:s}" == status.value
    assert f"[{status:>12}]" == f"[{status.value:>12}]"
    assert status == status.value and hash(status) == hash(status.value)
    data = report.to_json()
    assert data["status"] == status.value and type(data["status"]) is str
    assert data["exit_code"] == EXPECTED_CODES[status.value]
    out = tmp_path / "report.json"
    report.write(out)
    assert f'"status": "{status.value}"' in out.read_text()
    assert json.loads(out.read_text())["status"] == status.value
    assert json.dumps({"status": status}) == f'{{"status": "{status.value}"}}'


def test_a_report_made_with_a_string_status_holds_the_enum() -> None:
    report = RunReport(status="BUDGET", reason="", sim_time=0.0, wall_time=0.0,  # type: ignore[arg-type]
                       ticks=0)
    assert report.status is RunStatus.BUDGET and report.exit_code == 1
    assert report.summary().splitlines()[0] == "result: BUDGET"


def test_notes_end_the_summary_and_stay_out_of_the_json() -> None:
    report = RunReport(status=RunStatus.SUCCESS, reason="", sim_time=1.0, wall_time=1.0,
                       ticks=1, notes=["as built:", "  1. wall (x): installed, 1.0 mm, 0.10 deg"])
    assert report.summary().splitlines()[-2:] == report.notes
    assert "notes" not in report.to_json() and "as_built" not in report.to_json()
