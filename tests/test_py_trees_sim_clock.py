"""py_trees' time-based nodes run on the sim clock under ``bt-manip run --world``."""

from __future__ import annotations

import json
import time
from pathlib import Path

import pytest

from bt_manip.cli import main

ROOT = Path(__file__).resolve().parents[1]
TABLE = ROOT / "worlds" / "sawyer_table.yaml"


def _run(tmp_path: Path, body: str) -> tuple[int, dict, float]:  # type: ignore[type-arg]
    tree = tmp_path / "tree.xml"
    tree.write_text(f'<root BTCPP_format="4"><BehaviorTree ID="Main">{body}'
                    "</BehaviorTree></root>")
    report = tmp_path / "report.json"
    start = time.perf_counter()
    code = main(["run", str(tree), "--world", str(TABLE), "--quiet", "--report", str(report)])
    return code, json.loads(report.read_text()), time.perf_counter() - start


def test_timer_waits_on_the_sim_clock(tmp_path: Path) -> None:
    code, report, wall = _run(tmp_path, '<Timer duration="20"/>')
    assert code == 0 and report["status"] == "SUCCESS"
    # started at t = 0, SUCCESS at the first tick later than 20 s (ticks every 0.05 s)
    assert report["sim_time"] == pytest.approx(20.05, abs=1e-6)
    assert report["ticks"] == 402
    assert wall < report["sim_time"]  # sim seconds, not seconds of waiting


def test_py_trees_timeout_fails_on_the_sim_clock(tmp_path: Path) -> None:
    code, report, _ = _run(
        tmp_path, '<PyTreesTimeout duration="1"><Timer duration="30"/></PyTreesTimeout>')
    assert code == 1
    assert report["reason"] == "PyTreesTimeout: timed out"
    assert report["sim_time"] == pytest.approx(1.05, abs=1e-6) and report["ticks"] == 22
