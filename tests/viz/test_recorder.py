"""Recording a run into a replay page: poses, statuses, overlays, highlights, same outcome."""

from __future__ import annotations

import re
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import numpy as np
import pytest
from drive_tree import ROOM, DriveTree

from bt_manip.run.context import RunContext
from bt_manip.run.runner import Runner, RunOptions
from bt_manip.sim.events import Attached, Detached
from bt_manip.sim.world import World
from bt_manip.viz.recorder import Recorder, RecordOptions
from bt_manip.viz.replay_page import read_replay, track_samples
from bt_manip.viz.scene import ROOT

REPO = Path(__file__).resolve().parents[2]
STATUS = {"IDLE": 0, "RUNNING": 1, "SUCCESS": 2, "FAILURE": 3}


def _record(path: Path, hooks: list[Any] = (), **kw: Any) -> tuple[Any, dict, bytes, World]:
    world = World(ROOM, seed=3)
    tree = DriveTree(world)
    recorder = Recorder(path, world, tree, RecordOptions(**kw), info={"tree": "drive_tree"})
    report = Runner(tree, world, RunOptions(), on_tick=[*hooks, recorder]).run()
    recorder.close()
    header, blobs = read_replay(path)
    return report, header, blobs, world


def test_replay_holds_the_run(tmp_path: Path) -> None:
    page = tmp_path / "run.html"
    report, header, blobs, world = _record(page)
    try:
        assert report.status == "SUCCESS"
        # samples at 20 Hz of sim time, first and last included
        assert header["frames"]["count"] == pytest.approx(report.sim_time * 20 + 1, abs=2)
        assert header["duration"] == pytest.approx(report.sim_time, abs=1e-6)
        base = track_samples(header, blobs, f"{ROOT}/husky")
        x, y, _ = world.robots["husky"].base_pose2d()
        assert base[-1, :2] == pytest.approx([x, y], abs=1e-4)  # last frame = final pose
        assert np.linalg.norm(base[-1, :2] - base[0, :2]) > 1.0  # the robot drove > 1 m
        # the top plate does not move relative to the base: stored once
        tracks = {t["path"]: t for t in header["scene"]["tracks"]}
        assert tracks[f"{ROOT}/husky/top_plate_link"]["const"]
        assert not tracks[f"{ROOT}/husky/front_left_wheel_link"]["const"]
        # every mesh stored once; the four wheels share one
        names = [m["name"] for m in header["scene"]["meshes"]]
        assert names.count("wheel.stl") == 1
    finally:
        world.close()


def test_replay_holds_status_changes_with_reasons(tmp_path: Path) -> None:
    _, header, _, world = _record(tmp_path / "run.html")
    world.close()
    tree = header["tree"]
    names = [n["name"] for n in tree["nodes"]]
    assert names[:3] == ["mission", "drive", "turn"]
    assert tree["nodes"][names.index("plan_a")]["parent"] == names.index("recover")

    def changes(name: str) -> list[tuple[float, int, str]]:
        i = names.index(name)
        return [(t, c, tree["reasons"][r]) for t, j, c, r in tree["events"] if j == i]

    drive = changes("drive")
    assert [c for _, c, _ in drive][:2] == [STATUS["RUNNING"], STATUS["SUCCESS"]]
    assert drive[1][0] == pytest.approx(2.0, abs=0.06)  # drove for 2 s of sim
    fail = changes("plan_a")
    assert fail[0][1] == STATUS["FAILURE"]
    assert "doorway is blocked" in fail[0][2]
    assert changes("mission")[-1][1] == STATUS["SUCCESS"]
    assert header["result"] == "SUCCESS"


def test_replay_holds_overlays_and_highlights(tmp_path: Path) -> None:
    held: list[bool] = []

    def grab_at_one_second(runner: Any) -> None:
        # stand-in for an attach joint: announce the crate held from t = 1 s to 2 s
        world = runner.world
        holding = 1.0 <= world.time < 2.0
        if holding != bool(held and held[-1]):
            event = Attached if holding else Detached
            args = ("crate", "husky", "tool0") if holding else ("crate", "husky")
            world.events.announce(event(world.time, *args))
            held.append(holding)

    _, header, _, world = _record(tmp_path / "run.html", hooks=[grab_at_one_second])
    world.close()
    overlay = header["overlay"]
    names = {name for _, name, _, _ in overlay}
    assert {"drive_plan", "turn_plan", "target"} <= names
    first_plan = next(o for o in overlay if o[1] == "drive_plan")
    assert first_plan[2]["object"]["type"] == "Line"
    moves = [o for o in overlay if o[1] == "target" and o[2] is None]
    assert moves and len(moves[0][3]) == 16  # the triad moved: a new matrix only
    highlights = header["highlights"]
    assert [(name, on) for _, name, on in highlights] == [("crate", True), ("crate", False)]
    assert highlights[0][0] == pytest.approx(1.0, abs=0.06)
    assert header["scene"]["body_objects"]["crate"][0][1] == pytest.approx([0.2, 0.35, 0.85, 1])


def test_recording_does_not_change_the_run(tmp_path: Path) -> None:
    def run(record: bool) -> tuple[str, int, str]:
        world = World(ROOM, seed=3)
        tree = DriveTree(world)
        hooks: list[Any] = []
        if record:
            hooks.append(Recorder(tmp_path / "r.html", world, tree, RecordOptions(sample_hz=50)))
        report = Runner(tree, world, RunOptions(), on_tick=hooks).run()
        for hook in hooks:
            hook.close()
        snapshot = repr(world.snapshot())
        world.close()
        return report.status, report.ticks, snapshot

    assert run(False) == run(True)


def test_replay_page_is_self_contained(tmp_path: Path) -> None:
    page = tmp_path / "run.html"
    _, _, _, world = _record(page)
    world.close()
    text = page.read_text()
    assert page.stat().st_size < 25e6
    # nothing is fetched: no external scripts, styles, images or frames
    assert not re.search(r"<(script|link|img|iframe)[^>]+(src|href)=", text)
    assert "MeshCat" in text and 'id="bt-replay"' in text


def test_bodies_added_and_removed_during_the_run_keep_their_times(tmp_path: Path) -> None:
    from bt_manip.sim.world_spec import BodySpec, Part, Pose3D, Range2D

    def crate(name: str) -> BodySpec:
        return BodySpec(
            name=name, movable=True, parts=[Part("box", (0.3, 0.3, 0.3))], urdf=None,
            pose=Pose3D((-1.5, 1.5, 0.6)), planar=False, mass=2.0, friction=0.8,
            colour=(0.5, 0.3, 0.1, 1.0), randomize=Range2D(), line=0,
        )

    changes: dict[str, float] = {}

    def drop_and_take_crates(runner: Any) -> None:
        # what a block fault does (a crate falls), then DeleteModel, then the same name again
        world = runner.world
        for key, at, change in (("drop", 1.0, "spawn"), ("take", 2.0, "remove"),
                                ("again", 3.0, "spawn")):
            if key not in changes and world.time >= at:
                changes[key] = world.time
                if change == "spawn":
                    world.spawn(crate("crate_drop"))
                else:
                    world.remove("crate_drop")

    _, header, blobs, world = _record(tmp_path / "run.html", hooks=[drop_and_take_crates])
    world.close()
    bodies = {b["name"]: b for b in header["scene"]["bodies"]}
    first, second = bodies["crate_drop"], bodies["crate_drop~2"]
    assert first["appear"] == pytest.approx(changes["drop"], abs=1e-9)
    assert first["disappear"] == pytest.approx(changes["take"], abs=1e-9)
    assert second["appear"] == pytest.approx(changes["again"], abs=1e-9)
    assert second["disappear"] is None and bodies["husky"]["appear"] == 0.0
    assert f"{ROOT}/crate_drop~2/v0" in [o["path"] for o in header["scene"]["objects"]]
    times = np.frombuffer(blobs[header["frames"]["times"]["offset"]:][
        : header["frames"]["times"]["length"]], np.float32)
    track = next(t for t in header["scene"]["tracks"] if t["path"] == f"{ROOT}/crate_drop")
    # sampled from the tick it appeared at to the last sample before it was removed
    assert times[track["first"]] == pytest.approx(changes["drop"], abs=1e-6)
    assert times[track["first"] + track["count"] - 1] < changes["take"]
    fall = track_samples(header, blobs, f"{ROOT}/crate_drop")[:, 2]
    assert fall[0] == pytest.approx(0.6, abs=1e-6) and fall[-1] == pytest.approx(0.15, abs=0.01)


def test_a_block_fault_crate_is_in_the_replay(tmp_path: Path) -> None:
    import bt_manip.behaviours  # noqa: F401  (registers Navigate)
    from bt_manip.bt import load_tree_string
    from bt_manip.run.faults import FaultInjector, FaultSpec

    with World(REPO / "worlds" / "tb3_house.yaml", seed=0) as world:
        faults = FaultInjector([FaultSpec("block", 1.0)], seed=0, clock=world.clock)
        xml = ('<root BTCPP_format="4"><BehaviorTree ID="M"><Navigate goal="goal"/>'
               "</BehaviorTree></root>")
        context = RunContext.for_world(world, faults=faults)
        tree = load_tree_string(xml, context=context)
        recorder = Recorder(tmp_path / "crate.html", world, tree)
        dropped_at = None
        for _ in range(80):  # until the crate has been falling for a second
            tree.tick()
            recorder(SimpleNamespace(world=world))
            world.step(12)
            if dropped_at is None and "dropped_crate_0" in world.movable:
                dropped_at = world.time
            if dropped_at is not None and world.time > dropped_at + 1.0:
                break
        tree.halt()
        recorder.close()
    header, blobs = read_replay(tmp_path / "crate.html")
    crate = next(b for b in header["scene"]["bodies"] if b["name"] == "dropped_crate_0")
    assert crate["disappear"] is None and crate["path"] == f"{ROOT}/dropped_crate_0"
    z = track_samples(header, blobs, f"{ROOT}/dropped_crate_0")[:, 2]
    assert z[0] > z[-1] + 0.1  # it fell onto the route



def test_replay_holds_each_nodes_counts_of_a_bt_manip_trees_run(tmp_path: Path) -> None:
    from bt_manip.episode import Episode, EpisodeSpec

    page = tmp_path / "demo.html"
    tree = Path(__file__).resolve().parents[2] / "trees" / "builtins_demo.xml"
    with Episode(EpisodeSpec(tree=str(tree))) as episode:
        report = episode.run([Recorder(page, None, episode.tree)], RunOptions(tick_hz=1000))
    header, _ = read_replay(page)
    names = [n["name"] for n in header["tree"]["nodes"]]
    counts = header["tree"]["counts"]
    assert counts[names.index("plan_a")][:3] == [1, 0, 1]  # ticked once, failed once
    assert counts[names.index("third_time_lucky")][:3] == [3, 1, 2]
    assert len(counts) == len(report.nodes)


def test_a_py_trees_tree_has_no_counts_in_its_replay(tmp_path: Path) -> None:
    report, header, _, world = _record(tmp_path / "run.html")
    world.close()
    assert "counts" not in header["tree"]
    assert all(n.counts is None for n in report.nodes)
