"""`bt-manip run`: exit codes, run report, blackboard output, sim clock, Ctrl-C."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from processes import sigint_default
from tree_files import write_tree

from bt_manip.cli import main

ROOT = Path(__file__).resolve().parents[2]
TABLE = ROOT / "worlds" / "sawyer_table.yaml"


def test_builtins_demo_succeeds_and_writes_report_and_blackboard(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    report, bb = tmp_path / "report.json", tmp_path / "bb.json"
    code = main(
        [
            "run",
            str(ROOT / "trees" / "builtins_demo.xml"),
            "--report",
            str(report),
            "--bb-out",
            str(bb),
        ]
    )
    out = capsys.readouterr().out
    assert code == 0
    assert "result: SUCCESS" in out
    data = json.loads(report.read_text())
    assert data["status"] == "SUCCESS" and data["exit_code"] == 0
    assert data["ticks"] >= 2
    nodes = {n["path"]: n for n in data["nodes"]}
    assert nodes["demo/Fallback/plan_a"]["last_status"] == "FAILURE"
    assert json.loads(bb.read_text())["summary"] == "plan b, total 12"


def test_failing_tree_exits_1_with_the_failing_node(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    tree = write_tree(tmp_path, '<Sequence><AlwaysSuccess/><AlwaysFailure name="nope"/></Sequence>')
    assert main(["run", str(tree)]) == 1
    assert "result: FAILURE" in capsys.readouterr().out


def test_tick_budget_exits_1(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    tree = write_tree(tmp_path, '<Sleep msec="100000"/>')
    assert main(["run", str(tree), "--max-ticks", "3", "--tick-hz", "200"]) == 1
    assert "tick budget of 3 spent" in capsys.readouterr().out


def test_runtime_script_error_exits_2_naming_the_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    tree = write_tree(tmp_path, '<Sequence>\n<Script code="x := missing + 1"/>\n</Sequence>')
    assert main(["run", str(tree), "--quiet"]) == 2
    out = capsys.readouterr().out
    assert "result: ERROR" in out
    assert "line 4" in out and "missing" in out


def test_bad_tree_exits_2_without_traceback(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    tree = write_tree(tmp_path, "<Sequence><AlwaysSucces/></Sequence>")
    assert main(["run", str(tree)]) == 2
    err = capsys.readouterr().err
    assert f"{tree}:3:" in err and "AlwaysSuccess" in err and "Traceback" not in err


def test_durations_run_on_the_sim_clock(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    tree = write_tree(tmp_path, '<Sleep msec="30000"/>')
    report = tmp_path / "r.json"
    waits: list[float] = []
    monkeypatch.setattr(time, "sleep", waits.append)
    assert main(["run", str(tree), "--world", str(TABLE), "--quiet", "--report", str(report)]) == 0
    data = json.loads(report.read_text())
    assert data["sim_time"] == pytest.approx(30.0, abs=0.051)
    assert data["ticks"] == 601
    assert waits == []  # 30 s of sim, not of waiting
    assert data["seed"] == 0 and data["world"] == str(TABLE)


def test_ctrl_c_halts_and_exits_130(tmp_path: Path) -> None:
    tree = write_tree(tmp_path, '<Sleep msec="600000"/>')
    report = tmp_path / "r.json"
    proc = subprocess.Popen(
        [sys.executable, "-m", "bt_manip.cli", "run", str(tree), "--report", str(report)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env={**os.environ, "PYTHONUNBUFFERED": "1"},
        preexec_fn=sigint_default,
    )
    assert proc.stdout is not None
    first = proc.stdout.readline()  # the first status line: the tree is running
    assert "RUNNING" in first
    proc.send_signal(signal.SIGINT)
    out, err = proc.communicate(timeout=30)
    assert proc.returncode == 130, err
    assert "result: INTERRUPTED" in out
    assert "Traceback" not in err
    assert json.loads(report.read_text())["status"] == "INTERRUPTED"


def test_live_view_shows_what_finished_nodes_returned() -> None:
    from bt_manip.bt import TreeContext, load_tree
    from bt_manip.bt.display import render_status
    from bt_manip.clock import ManualClock

    clock = ManualClock()
    tree = load_tree(str(ROOT / "trees" / "builtins_demo.xml"), context=TreeContext(clock=clock))
    assert "[ ] Script 'init'" in render_status(tree)  # not run yet
    for _ in range(100):
        if tree.tick().name == "SUCCESS":
            break
        clock.advance(0.05)
    view = render_status(tree)
    assert "[+] Script 'init'" in view
    assert "[x] AlwaysFailure 'plan_a'" in view
    assert "[+] Sleep 'short_wait'" in view


def test_groot_model_lists_the_robot_nodes_with_their_ports(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    import xml.etree.ElementTree as ET

    assert main(["nodes", "--groot"]) == 0
    text = capsys.readouterr().out
    model = tmp_path / "model.xml"
    model.write_text(text)
    nodes = {el.get("ID"): el for el in ET.fromstring(text).find("TreeNodesModel")}
    robot_nodes = {
        "Navigate",
        "Reverse",
        "GetClear",
        "MoveJointsSequentially",
        "MoveJoints",
        "MoveToPose",
        "Lift",
        "OpenGripper",
        "CloseGripper",
        "Attach",
        "Detach",
        "IsAttached",
        "IsHolding",
        "ObjectInRegion",
        "ObjectAbove",
        "CarriedClear",
        "SpawnModel",
        "DeleteModel",
        "DropPoint",
    }
    assert robot_nodes <= set(nodes)
    assert "Sequence" not in nodes and "Timeout" not in nodes  # built-ins are not listed
    ports = {p.get("name"): p for p in nodes["MoveJointsSequentially"]}
    assert {"targets", "order", "units", "tolerance", "speed"} <= set(ports)
    assert ports["targets"].get("type") == "std::vector<double>"
    assert nodes["CloseGripper"].tag == "Action" and nodes["IsAttached"].tag == "Condition"
    drop = {p.get("name"): p for p in nodes["DropPoint"]}
    assert drop["point"].tag == "output_port" and drop["index"].tag == "input_port"
    # the model file loads back: the scenario trees validate against it
    for scenario in ("husky_carry_wall.xml", "sawyer_blocks_to_bin.xml"):
        assert main(["validate", str(ROOT / "trees" / scenario), "--models", str(model)]) == 0


def test_bb_numbers_feed_ports_of_any_number_type_and_scripts(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # `--bb t=3` holds the integer 3; a double port (CloseGripper's timeout) reads it, and a
    # script computes with it, as with an entry a script created
    tree = write_tree(
        tmp_path,
        '    <Sequence><CloseGripper timeout="{t}"/><Script code="u := t + 0.5"/></Sequence>',
    )
    bb = tmp_path / "bb.json"
    code = main(["run", str(tree), "--world", str(TABLE), "--quiet", "--bb", "t=3",
                 "--bb-out", str(bb)])
    assert code == 0, capsys.readouterr()
    assert json.loads(bb.read_text())["u"] == 3.5
