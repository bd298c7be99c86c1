"""bench writes its episodes as they finish, resumes an interrupted bench, sweeps a value, and
its outputs follow the JSON Schemas of docs/schemas."""

from __future__ import annotations

import json
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

from bt_manip.bench.log import LOG_NAME, read_log
from bt_manip.cli import main
from tests.bench.interrupts import interrupted_when

ROOT = Path(__file__).resolve().parents[2]
SCHEMAS = ROOT / "docs" / "schemas"
WORLD = str(ROOT / "worlds" / "sawyer_table.yaml")


def _tree(tmp_path: Path) -> Path:
    """A tree whose outcome depends on the seed (through an injected failure), quick to run."""
    tree = tmp_path / "steps.xml"
    tree.write_text(
        '<root BTCPP_format="4"><BehaviorTree ID="Main"><Sequence>'
        '<Sleep msec="300"/><Script code="n := 7"/><AlwaysSuccess name="step"/>'
        "</Sequence></BehaviorTree></root>"
    )
    return tree


def _outcomes(folder: Path) -> list[tuple[Any, ...]]:
    data = json.loads((folder / "episodes.json").read_text())
    return [(e["seed"], e["status"], e["sim_time"], e["ticks"], e["metrics"], e["injected"])
            for e in data["episodes"]]


def _bench(tree: Path, out: Path, *extra: str) -> int:
    return main(["bench", str(tree), "--world", WORLD, "--runs", "6", "--jobs", "1",
                 "--inject", "step:failure:0.7", "--out", str(out), *extra])


def test_an_interrupted_bench_keeps_its_episodes_and_resume_completes_it(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    tree = _tree(tmp_path)
    assert _bench(tree, tmp_path / "whole") == 1  # some seeds draw the failure
    with interrupted_when(monkeypatch, lambda spec: spec.seed == 3):
        assert _bench(tree, tmp_path / "cut") == 130
    assert "continue with: bt-manip bench --resume" in capsys.readouterr().out
    logged = read_log(tmp_path / "cut")
    assert [r.seed for r in logged.results] == [0, 1, 2]
    assert logged.missing == [3, 4, 5]
    assert not (tmp_path / "cut" / "episodes.json").exists()

    # a line cut short by a crash is dropped, and the bench goes on after the whole lines
    with open(tmp_path / "cut" / LOG_NAME, "a") as fh:
        fh.write('{"kind": "episode", "seed": 3, "sta')
    assert main(["bench", "--resume", str(tmp_path / "cut"), "--jobs", "2"]) == 1
    assert _outcomes(tmp_path / "cut") == _outcomes(tmp_path / "whole")
    lines = (tmp_path / "cut" / LOG_NAME).read_text().splitlines()
    assert len(lines) == 7 and all(json.loads(line) for line in lines)
    # nothing left to run: resuming again changes nothing
    assert main(["bench", "--resume", str(tmp_path / "cut")]) == 1
    assert len((tmp_path / "cut" / LOG_NAME).read_text().splitlines()) == 7


def _interrupt_from_compiled_code() -> None:
    """What Python raises when a Ctrl-C comes while a compiled (numba) function runs."""
    try:
        raise KeyboardInterrupt
    except KeyboardInterrupt as ctrl_c:
        raise SystemError("CPUDispatcher(<function _search>) returned a result with an "
                          "exception set") from ctrl_c


def _raise_keyboard_interrupt() -> None:
    raise KeyboardInterrupt


@pytest.mark.parametrize("interrupt", [_raise_keyboard_interrupt, _interrupt_from_compiled_code])
def test_ctrl_c_during_an_episode_stops_a_one_process_bench(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch, interrupt: Callable[[], None]) -> None:
    """The runner turns a Ctrl-C into an INTERRUPTED run (tree halted, robots stopped), also
    one that comes while compiled code runs; the bench then stops too, keeping only the
    episodes that finished."""
    from bt_manip.sim.world import World

    tree = _tree(tmp_path)
    real_step = World.step

    def ctrl_c_in_seed_2(self: World, n: int = 1) -> None:
        if self.seed == 2 and self.time > 0.1:
            interrupt()
        real_step(self, n)

    monkeypatch.setattr(World, "step", ctrl_c_in_seed_2)
    assert _bench(tree, tmp_path / "cut") == 130
    logged = read_log(tmp_path / "cut")
    assert [(r.seed, r.status in ("SUCCESS", "FAILURE")) for r in logged.results] == [
        (0, True), (1, True)]
    assert logged.missing == [2, 3, 4, 5]


def test_resume_refuses_a_changed_tree_and_options_that_redefine_the_bench(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    tree = _tree(tmp_path)
    assert _bench(tree, tmp_path / "b") == 1
    capsys.readouterr()
    assert main(["bench", "--resume", str(tmp_path / "b"), "--runs", "9"]) == 2
    assert "leave out --runs" in capsys.readouterr().err
    tree.write_text(tree.read_text().replace("300", "400"))
    assert main(["bench", "--resume", str(tmp_path / "b")]) == 2
    err = capsys.readouterr().err
    assert "steps.xml" in err and "changed since the bench" in err
    assert main(["bench", "--resume", str(tmp_path / "nothing")]) == 2
    assert "nothing to resume" in capsys.readouterr().err


def test_bench_without_tree_or_world_says_what_is_missing(
        capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["bench", "--world", WORLD]) == 2
    assert "TREE required (or --resume DIR)" in capsys.readouterr().err


@pytest.mark.parametrize(("text", "why"), [
    ("slip:0.1", "exactly one {a,b,...}"),
    ("slip:{0,,1}", "an empty value"),
    ("slip:{0,0}", "given twice"),
    ("slip:{0,2}", "value '2'"),
    ("bb:{a,b}", "expected bb:KEY={a,b,...}"),
])
def test_bad_sweeps_are_input_errors(tmp_path: Path, text: str, why: str,
                                     capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["bench", str(_tree(tmp_path)), "--world", WORLD, "--runs", "1",
                 "--sweep", text, "--out", str(tmp_path / "s")]) == 2
    assert why in capsys.readouterr().err


def test_a_sweep_runs_the_same_seeds_at_each_value_and_plots_the_success_rate(
        tmp_path: Path) -> None:
    tree = _tree(tmp_path)
    out = tmp_path / "sweep"
    code = main(["bench", str(tree), "--world", WORLD, "--runs", "4", "--jobs", "1",
                 "--sweep", "step:failure:{0,1}", "--out", str(out)])
    assert code == 1
    plan = json.loads((out / "sweep.json").read_text())
    assert [(p["value"], p["successes"], p["runs"]) for p in plan["points"]] == [
        ("0", 4, 4), ("1", 0, 4)]
    for point in plan["points"]:
        seeds = [e["seed"] for e in json.loads(
            (out / point["folder"] / "episodes.json").read_text())["episodes"]]
        assert seeds == [0, 1, 2, 3]
    assert (out / "sweep.png").stat().st_size > 0
    rows = (out / "sweep.csv").read_text().splitlines()
    assert rows[0].startswith("schema_version,value,runs,successes,success_rate")
    assert len(rows) == 3
    # bb sweeps set the entry for every episode
    code = main(["bench", str(tree), "--world", WORLD, "--runs", "1", "--jobs", "1",
                 "--sweep", "bb:speed={0.5,2}", "--out", str(tmp_path / "bb")])
    assert code == 0
    plan = json.loads((tmp_path / "bb" / "sweep.json").read_text())
    folders = [tmp_path / "bb" / p["folder"] for p in plan["points"]]
    speeds = [json.loads((f / "episodes.json").read_text())["episodes"][0]["metrics"]["speed"]
              for f in folders]
    assert speeds == [0.5, 2.0]


def test_bench_outputs_follow_their_json_schemas(tmp_path: Path) -> None:
    jsonschema = pytest.importorskip("jsonschema")
    from referencing import Registry, Resource

    schemas = {p.name: json.loads(p.read_text()) for p in SCHEMAS.glob("*.schema.json")}
    registry: Registry = Registry().with_resources(
        (s["$id"], Resource.from_contents(s)) for s in schemas.values())

    def check(instance: Any, name: str) -> None:
        jsonschema.Draft202012Validator(schemas[name], registry=registry).validate(instance)

    tree = _tree(tmp_path)
    out = tmp_path / "b"
    assert _bench(tree, out) == 1
    check(json.loads((out / "episodes.json").read_text()), "bench-episodes.schema.json")
    check(json.loads((out / "summary.json").read_text()), "bench-summary.schema.json")
    header, *episodes = (out / LOG_NAME).read_text().splitlines()
    check(json.loads(header), "bench-log-header.schema.json")
    for line in episodes:
        check(json.loads(line), "bench-episode.schema.json")
    assert main(["bench", str(tree), "--world", WORLD, "--runs", "2", "--jobs", "1",
                 "--sweep", "slip:{0,0.5}", "--out", str(tmp_path / "s")]) == 0
    check(json.loads((tmp_path / "s" / "sweep.json").read_text()), "bench-sweep.schema.json")
    with pytest.raises(jsonschema.ValidationError):
        check({"schema_version": 1, "episodes": []}, "bench-episodes.schema.json")


def test_an_interrupted_sweep_resumes_value_by_value(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    tree = _tree(tmp_path)
    args = ["bench", str(tree), "--world", WORLD, "--runs", "3", "--jobs", "1",
            "--sweep", "step:failure:{0,1}"]
    assert main([*args, "--out", str(tmp_path / "whole")]) == 1
    with interrupted_when(
            monkeypatch, lambda spec: spec.seed == 1 and spec.inject[-1].probability == 1.0):
        assert main([*args, "--out", str(tmp_path / "cut")]) == 130
    assert main(["bench", "--resume", str(tmp_path / "cut")]) == 1
    for folder in ("00_0", "01_1"):
        assert _outcomes(tmp_path / "cut" / folder) == _outcomes(tmp_path / "whole" / folder)
    plan = json.loads((tmp_path / "cut" / "sweep.json").read_text())
    assert [p["successes"] for p in plan["points"]] == [3, 0]
