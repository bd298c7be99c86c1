"""Fault specifications, seeded fault draws and bench statistics."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from processes import sigint_default

from bt_manip.bench.episodes import EpisodeResult
from bt_manip.bench.stats import summarise, wilson_interval
from bt_manip.cli import main
from bt_manip.episode import EpisodeSpec
from bt_manip.errors import InputError
from bt_manip.run.faults import FaultInjector, FaultSpec, parse_fault


@pytest.mark.parametrize(
    ("text", "spec"),
    [
        ("Attach:failure:0.3", FaultSpec("failure", 0.3, "Attach")),
        ("grasp_panel:failure:1", FaultSpec("failure", 1.0, "grasp_panel")),
        ("slip:0.2", FaultSpec("slip", 0.2)),
        ("block:0", FaultSpec("block", 0.0)),
        ("pose_noise:0.01", FaultSpec("pose_noise", 0.0, sigma_m=0.01, sigma_deg=2.0)),
        ("pose_noise:0.02:5", FaultSpec("pose_noise", 0.0, sigma_m=0.02, sigma_deg=5.0)),
        ("pose_noise:0:0", FaultSpec("pose_noise", 0.0)),
    ],
)
def test_parse_fault(text: str, spec: FaultSpec) -> None:
    assert parse_fault(text) == spec
    assert parse_fault(spec.text()) == spec


@pytest.mark.parametrize(
    ("text", "why"),
    [
        ("Attach:failure:1.5", "not within 0..1"),
        ("Attach:failure:often", "is not a number"),
        ("Attach:0.3", "unknown fault kind 'Attach' (for a node, write Attach:failure:0.3)"),
        ("rain:0.3", "unknown fault kind 'rain' (for a node, write rain:failure:0.3)"),
        ("slp:0.3", "unknown fault kind 'slp' (did you mean 'slip'?)"),
        ("Attach:failur:0.3", "unknown fault kind 'failur' (did you mean 'failure'?)"),
        ("pose_nois:0.01", "unknown fault kind 'pose_nois' (did you mean 'pose_noise'?)"),
        ("pose_noise:abc", "sigma 'abc' is not a number"),
        ("pose_noise:-0.01", "sigma -0.01 m is not within 0..0.5 m"),
        ("pose_noise:0.6", "sigma 0.6 m is not within 0..0.5 m"),
        ("pose_noise:nan", "sigma nan m is not within 0..0.5 m"),
        ("pose_noise:0.01:91", "sigma 91 deg is not within 0..90 deg"),
        ("pose_noise:0.01:2:3", "pose_noise takes a position sigma in metres"),
        ("pose_noise", "pose_noise takes a position sigma in metres"),
    ],
)
def test_bad_fault_is_an_input_error(text: str, why: str) -> None:
    with pytest.raises(InputError) as err:
        parse_fault(text)
    assert why in str(err.value)
    assert "expected NAME:failure:P, slip:P, block:P or pose_noise:SIGMA_M[:SIGMA_DEG]" in str(
        err.value
    )


def test_fault_draws_are_seeded_and_match_probability() -> None:
    specs = [FaultSpec("failure", 0.3, "Attach")]
    a = FaultInjector(specs, seed=5)
    b = FaultInjector(specs, seed=5)
    draws_a = [a.node_fails("grasp", "Attach") for _ in range(2000)]
    draws_b = [b.node_fails("grasp", "Attach") for _ in range(2000)]
    assert draws_a == draws_b
    assert 0.26 < sum(draws_a) / 2000 < 0.34
    assert len(a.events) == sum(draws_a)
    assert not any(FaultInjector(specs, seed=5).node_fails("grasp", "Detach") for _ in range(100))
    c = FaultInjector(specs, seed=6)
    assert [c.node_fails("x", "Attach") for _ in range(2000)] != draws_a


def test_wilson_interval() -> None:
    lo, hi = wilson_interval(49, 50)
    assert lo == pytest.approx(0.8950, abs=1e-3)
    assert hi == pytest.approx(0.9965, abs=1e-3)
    assert wilson_interval(0, 10)[0] == 0.0
    assert wilson_interval(10, 10)[1] == pytest.approx(1.0)


def test_summary_counts_failures_by_node_and_reason() -> None:
    results = [
        EpisodeResult(0, "SUCCESS", "", 60.0, 6.0, 1200),
        EpisodeResult(1, "FAILURE", "root/grasp: too far", 30.0, 3.0, 600, "Attach"),
        EpisodeResult(2, "FAILURE", "root/grasp: too far", 31.0, 3.0, 620, "Attach"),
        EpisodeResult(3, "BUDGET", "time budget of 90 s spent", 90.0, 9.0, 1800, "Navigate"),
    ]
    s = summarise(results, EpisodeSpec(tree="t.xml", world="w.yaml"))
    assert (s.runs, s.successes, s.success_rate) == (4, 1, 0.25)
    assert s.failures[0] == {"node": "Attach", "reason": "root/grasp: too far", "count": 2}
    assert s.sim_time["median"] == pytest.approx(45.5)
    assert s.real_time_factor["median"] == pytest.approx(10.0)
    assert "success: 1/4 = 25.0 %" in s.text()


def _retry_tree(tmp_path: Path) -> Path:
    tree = tmp_path / "retry.xml"
    tree.write_text(
        '<root BTCPP_format="4"><BehaviorTree ID="Main">'
        '<RetryUntilSuccessful num_attempts="4"><AlwaysSuccess name="step"/>'
        "</RetryUntilSuccessful></BehaviorTree></root>"
    )
    return tree


def test_injected_failures_reach_the_tree_and_the_report(tmp_path: Path) -> None:
    tree = _retry_tree(tmp_path)
    report = tmp_path / "r.json"
    assert (
        main(["run", str(tree), "--quiet", "--inject", "step:failure:1", "--report", str(report)])
        == 1
    )
    data = json.loads(report.read_text())
    assert data["extra"]["inject"] == ["step:failure:1"]
    assert [e["target"] for e in data["extra"]["injected"]] == ["step"] * 4
    steps = [n for n in data["nodes"] if n["path"].endswith("/step")]
    assert steps[0]["reason"] == "injected failure (--inject)"
    # by node ID too, and retries recover from occasional failures the same way every time
    codes = [
        main(["run", str(tree), "--quiet", "--seed", "3", "--inject", "AlwaysSuccess:failure:0.5"])
        for _ in range(2)
    ]
    assert codes[0] == codes[1]
    assert main(["run", str(tree), "--quiet", "--inject", "step:failure:0"]) == 0


def test_a_tree_with_injected_failures_looks_node_for_node_like_the_tree(tmp_path: Path) -> None:
    from bt_manip.bt import to_xml
    from bt_manip.episode import Episode
    from bt_manip.viz.tree_state import TreeWatcher

    tree = tmp_path / "nested.xml"
    tree.write_text(
        '<root BTCPP_format="4" main_tree_to_execute="Main">'
        '<BehaviorTree ID="Main"><Sequence name="mission"><Script code="fails := 0"/>'
        '<RetryUntilSuccessful num_attempts="3">'
        '<AlwaysSuccess name="step" _onFailure="fails += 1"/></RetryUntilSuccessful>'
        '<Fallback><AlwaysFailure name="plan_a"/><SubTree ID="PlanB"/></Fallback>'
        "</Sequence></BehaviorTree>"
        '<BehaviorTree ID="PlanB"><Sequence><AlwaysSuccess name="plan_b"/>'
        "</Sequence></BehaviorTree></root>"
    )
    inject = [parse_fault("step:failure:1"), parse_fault("plan_b:failure:0.5")]

    def seen(spec: EpisodeSpec) -> tuple[object, ...]:
        with Episode(spec) as episode:
            nodes = episode.tree.nodes()
            shape = (
                [(type(n), n.name, n.NODE_ID) for n in nodes],
                TreeWatcher(episode.tree).structure(),
                to_xml(episode.tree),
            )
            report = episode.run()
            fails = episode.tree.blackboard.get("fails")
        return shape, [(n.path, n.node) for n in report.nodes], report, fails

    plain_shape, plain_paths, plain, _ = seen(EpisodeSpec(tree=str(tree)))
    faulty_shape, faulty_paths, faulty, fails = seen(EpisodeSpec(tree=str(tree), inject=inject))
    assert faulty_shape == plain_shape
    assert faulty_paths == plain_paths
    assert any(path.endswith("/plan_b") for path, _ in plain_paths)  # inside the subtree
    assert plain.status == "SUCCESS"
    # the failures still happen: the step fails each of its three attempts, and its
    # _onFailure script runs as for any failure
    assert faulty.status == "FAILURE"
    assert [e["target"] for e in faulty.extra["injected"]] == ["step"] * 3
    assert fails == 3
    step = next(n for n in faulty.nodes if n.path.endswith("/step"))
    assert step.reason == "injected failure (--inject)"


def test_bench_runs_episodes_in_processes_and_writes_outputs(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    root = Path(__file__).resolve().parents[2]
    tree = tmp_path / "t.xml"
    tree.write_text(
        '<root BTCPP_format="4"><BehaviorTree ID="Main"><Sequence>'
        '<Script code="blocks := 3"/><Sleep msec="500"/>'
        '<AlwaysSuccess name="maybe" />'
        "</Sequence></BehaviorTree></root>"
    )
    out = tmp_path / "bench"
    code = main(
        [
            "bench",
            str(tree),
            "--world",
            str(root / "worlds" / "sawyer_table.yaml"),
            "--runs",
            "4",
            "--jobs",
            "2",
            "--out",
            str(out),
            "--inject",
            "maybe:failure:0.5",
            "--seed",
            "1",
        ]
    )
    text = capsys.readouterr().out
    summary = json.loads((out / "summary.json").read_text())
    listed = json.loads((out / "episodes.json").read_text())
    assert listed["schema_version"] == summary["schema_version"] == 3
    episodes = listed["episodes"]
    assert [e["seed"] for e in episodes] == [1, 2, 3, 4]
    assert summary["runs"] == 4
    assert summary["successes"] == sum(e["status"] == "SUCCESS" for e in episodes)
    assert code == (0 if summary["successes"] == 4 else 1)
    assert all(e["sim_time"] == pytest.approx(0.5, abs=0.06) for e in episodes)
    assert summary["metrics"]["blocks"]["mean"] == 3.0
    assert summary["injected"].get("failure", 0) == 4 - summary["successes"]
    failed = [e for e in episodes if e["status"] == "FAILURE"]
    assert [e["failed_node"] for e in failed] == ["maybe (AlwaysSuccess)"] * len(failed)
    assert (out / "episodes.csv").read_text().splitlines()[0].endswith("injected,blocks")
    assert (out / "outcomes.png").stat().st_size > 1000
    assert f"success: {summary['successes']}/4" in text


def test_outcomes_plot_has_integer_seed_and_count_ticks() -> None:
    from bt_manip.bench.files import outcomes_figure

    results = [
        EpisodeResult(3, "SUCCESS", "", 0.8, 0.1, 16),
        EpisodeResult(4, "FAILURE", "Sequence/x: no", 0.5, 0.1, 10, "x"),
        EpisodeResult(5, "SUCCESS", "", 0.8, 0.1, 16),
    ]
    fig = outcomes_figure(results, summarise(results, EpisodeSpec(tree="t.xml", world="w.yaml")))
    left, right = fig.axes
    fig.canvas.draw()
    seeds = [t for t in left.get_xticks() if left.get_xlim()[0] <= t <= left.get_xlim()[1]]
    counts = [t for t in right.get_yticks() if right.get_ylim()[0] <= t <= right.get_ylim()[1]]
    assert seeds and all(float(t).is_integer() for t in seeds)
    assert counts and all(float(t).is_integer() for t in counts)
    assert right.get_title() == "histogram of sim time per episode (3 episodes)"
    assert right.get_xlabel() == "sim time per episode (s)"
    import matplotlib.pyplot as plt

    plt.close(fig)


def test_bench_ctrl_c_stops_the_workers_and_exits_130(tmp_path: Path) -> None:
    import os
    import signal
    import subprocess
    import sys

    root = Path(__file__).resolve().parents[2]
    tree = tmp_path / "long.xml"
    tree.write_text(
        '<root BTCPP_format="4"><BehaviorTree ID="Main"><Sleep msec="3600000"/>'
        "</BehaviorTree></root>"
    )
    proc = subprocess.Popen(
        [sys.executable, "-m", "bt_manip.cli", "bench", str(tree), "--world",
         str(root / "worlds" / "sawyer_table.yaml"), "--runs", "6", "--jobs", "2",
         "--out", str(tmp_path / "out")],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env={**os.environ, "PYTHONUNBUFFERED": "1"},
        start_new_session=True,  # Ctrl-C reaches the whole process group, workers included
        preexec_fn=sigint_default,
    )
    assert proc.stdout is not None
    assert proc.stdout.readline().startswith("bench: 6 episodes")  # the workers are starting
    os.killpg(proc.pid, signal.SIGINT)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 130, err
    assert "interrupted" in err.splitlines()
    # no episode finished: the log holds the bench's definition only, ready for --resume
    lines = (tmp_path / "out" / "episodes.jsonl").read_text().splitlines()
    assert len(lines) == 1 and '"kind": "bench"' in lines[0]
    assert not (tmp_path / "out" / "episodes.json").exists()


class _Room:
    """A stand-in world for the ``block`` fault: records what is spawned, or refuses it."""

    def __init__(self, refuse: str = "") -> None:
        self.movable: dict[str, int] = {}
        self.spawned: list[object] = []
        self.refuse = refuse

    def spawn(self, spec: object) -> int:
        if self.refuse:
            raise ValueError(self.refuse)
        self.spawned.append(spec)
        return 1


def test_the_block_fault_drops_a_crate_mid_route_or_says_why_not() -> None:
    import numpy as np

    from bt_manip.run.faults import BLOCK_SIZE, CRATE_DROP_HEIGHT, CRATE_MASS, block_route

    route = np.array([[0.0, 0.0], [1.0, 0.0], [2.0, 0.0], [3.0, 0.0], [4.0, 0.0]])
    room = _Room()
    injector = FaultInjector([FaultSpec("block", 1.0)])
    assert block_route(room, injector, route, "goal") == "dropped_crate_0"
    (crate,) = room.spawned
    assert crate.pose.xyz == (2.0, 0.0, BLOCK_SIZE / 2 + CRATE_DROP_HEIGHT)  # type: ignore[attr-defined]
    assert crate.mass == CRATE_MASS  # type: ignore[attr-defined]
    assert injector.report() == [{"kind": "block", "target": "goal", "sim_time": 0.0}]
    # a route too short to have a point 1.5 m from both ends gets no crate, and draws nothing
    assert block_route(room, injector, route[:3], "near") is None
    assert len(injector.events) == 1
    refused = FaultInjector([FaultSpec("block", 1.0)])
    why = "'dropped_crate_0' would start 40 mm inside 'sofa'"
    assert block_route(_Room(refuse=why), refused, route, "goal") is None
    assert refused.report()[0]["note"] == f"no crate fell: {why}"


def test_pose_noise_is_drawn_once_per_object_and_seed() -> None:
    spec = parse_fault("pose_noise:0.01")
    a = FaultInjector([spec], seed=3)
    b = FaultInjector([spec], seed=3)
    first = a.pose_offset("panel")
    assert first is not None
    assert a.pose_offset("panel") == first  # once per episode: asked again, the same
    # another object's draw does not depend on what was drawn before
    crate_b = b.pose_offset("crate")
    assert b.pose_offset("panel") == first
    assert a.pose_offset("crate") == crate_b != first
    assert FaultInjector([spec], seed=4).pose_offset("panel") != first
    assert FaultInjector([], seed=3).pose_offset("panel") is None
    # the report lists what was drawn, once per object
    assert [(e["kind"], e["target"]) for e in a.report()] == [
        ("pose_noise", "panel"), ("pose_noise", "crate")
    ]
    assert a.report()[0]["note"].startswith("dx=")


def test_pose_noise_sigmas_are_those_asked_for() -> None:
    spec = parse_fault("pose_noise:0.01:2")
    draws = [FaultInjector([spec], seed=s).pose_offset("panel") for s in range(400)]
    dx = np.array([d.dx for d in draws if d is not None])
    dyaw = np.array([d.dyaw for d in draws if d is not None])
    assert len(dx) == 400
    assert 0.008 < float(np.std(dx)) < 0.012
    assert 0.8 * np.radians(2) < float(np.std(dyaw)) < 1.2 * np.radians(2)


def test_bench_lists_the_leaves_that_failed_and_in_how_many_episodes(tmp_path: Path) -> None:
    from bt_manip.bench.episodes import run_one

    tree = _retry_tree(tmp_path)
    results = [
        run_one(EpisodeSpec(tree=str(tree), seed=seed,
                            inject=[parse_fault("step:failure:0.5")]))
        for seed in range(8)
    ]
    for r in results:
        drawn = sum(1 for e in r.injected if e["target"] == "step")
        # every injected failure of the leaf is counted, and nothing else failed
        assert r.leaf_failures == ({"RetryUntilSuccessful/step": drawn} if drawn else {})
    s = summarise(results, EpisodeSpec(tree=str(tree)))
    failed = [r for r in results if r.leaf_failures]
    assert failed, "the seeds drew no failure"
    assert s.leaf_failures == [{
        "path": "RetryUntilSuccessful/step",
        "episodes": len(failed),
        "times": sum(r.leaf_failures["RetryUntilSuccessful/step"] for r in failed),
    }]
    assert "actions that failed (episodes, times):" in s.text()
