"""The live viewer: meshcat server, tree page, and going on headless when it cannot run."""

from __future__ import annotations

import json
import socket
import urllib.request
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from drive_tree import ROOM, DriveTree

from bt_manip.cli import main
from bt_manip.run.runner import Runner, RunOptions
from bt_manip.sim.world import World
from bt_manip.viz.live import LiveOptions, LiveViewer
from bt_manip.viz.replay_page import read_replay
from bt_manip.viz.tree_page import PortUnavailable

REPO = Path(__file__).resolve().parents[2]


def _get(url: str) -> Any:
    with urllib.request.urlopen(url, timeout=5) as res:
        return json.loads(res.read())


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def _run(viewer: bool, options: LiveOptions | None = None, hooks: list[Any] = ()) -> tuple:
    world = World(ROOM, seed=3)
    tree = DriveTree(world)
    live = LiveViewer(world, tree, options or LiveOptions(port=0), say=lambda s: None)
    started = live.start() if viewer else False
    report = Runner(tree, world, RunOptions(), on_tick=[*hooks, live] if started else hooks).run()
    result = (report.status, report.ticks, repr(world.snapshot()))
    return result, live, world


def test_live_viewer_draws_and_serves_statuses() -> None:
    # kept serving after the run (as --keep-serving does), to be read here
    options = LiveOptions(port=0, max_fps=1e6, keep_serving=True)
    (status, ticks, _), live, world = _run(True, options)
    try:
        assert status == "SUCCESS" and live.page is not None and live.link is not None
        assert live.updates == ticks  # one scene update per tick when not throttled
        tree = _get(live.page.url + "tree.json")
        names = [n["name"] for n in tree["nodes"]]
        assert names[:3] == ["mission", "drive", "turn"]
        state = _get(live.page.url + "state.json")
        assert state["ticks"] == ticks and state["result"] == "SUCCESS"
        assert state["statuses"][names.index("drive")] == 2
        # plan_a failed for one tick and was reset; the page still lists why
        (t, index, reason), = state["failures"]
        assert names[index] == "plan_a" and "doorway is blocked" in reason and t > 3.0
        assert "doorway is blocked" in state["reasons"][names.index("plan_a")]
        assert state["statuses"][names.index("plan_a")] == 3  # shown FAILURE, not IDLE
        with urllib.request.urlopen(live.page.url, timeout=5) as res:
            page = res.read().decode()
        assert live.link.web_url in page and "static/live.js" in page
        # the meshcat server holds the drawn scene (what a newly opened view receives)
        html = live.link._request(b"get_scene").decode()
        assert html.count("fetch(") >= len(live.scene.objects) if live.scene else False
    finally:
        live.stop()
        world.close()
    assert live.link is None and live.page is None


def test_same_run_with_and_without_the_viewer() -> None:
    with_view, live, world = _run(True)
    live.close()
    world.close()
    without, _, world = _run(False)
    world.close()
    assert with_view == without


def test_unreachable_server_warns_once_and_goes_headless(capsys: pytest.CaptureFixture) -> None:
    url = f"tcp://127.0.0.1:{_free_port()}"
    headless, _, world = _run(False)
    world.close()
    result, live, world = _run(True, LiveOptions(zmq_url=url, port=0, timeout=0.3))
    world.close()
    err = capsys.readouterr().err
    assert not live.active and live.page is None
    assert err.count("warning:") == 1 and "no answer from the meshcat server" in err
    assert result == headless


def test_server_lost_mid_run_warns_once(capsys: pytest.CaptureFixture) -> None:
    holder: dict[str, LiveViewer] = {}

    def kill_server(runner: Any) -> None:
        live = holder.get("live")
        if runner.ticks == 10 and live is not None and live.link is not None:
            live.link.server.kill()
            live.link.server.wait()

    world = World(ROOM, seed=3)
    tree = DriveTree(world)
    live = LiveViewer(world, tree, LiveOptions(port=None, timeout=0.3, max_fps=1000),
                      say=lambda s: None)
    holder["live"] = live
    assert live.start()
    report = Runner(tree, world, RunOptions(), on_tick=[kill_server, live]).run()
    live.close()
    world.close()
    assert report.status == "SUCCESS"
    assert capsys.readouterr().err.count("warning:") == 1


def test_taken_port_is_refused_before_anything_starts() -> None:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        s.listen()
        port = s.getsockname()[1]
        world = World(ROOM, seed=3)
        live = LiveViewer(world, DriveTree(world), LiveOptions(port=port), say=lambda s: None)
        try:
            with pytest.raises(PortUnavailable) as caught:
                live.start()
            assert caught.value.in_use and caught.value.flag == "--port"
            assert caught.value.strerror == (
                f"port {port} is in use on 127.0.0.1 (another bt-manip --viz?); choose another "
                "port, or 0 for any free one"
            )
            assert live.page is None and live.link is None  # no meshcat server was started
        finally:
            live.close()
            world.close()


def test_cli_record_and_unreachable_viewer(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    out = tmp_path / "demo.html"
    tree = str(REPO / "trees" / "builtins_demo.xml")
    code = main(["run", tree, "--world", str(ROOM), "--quiet", "--record", str(out),
                 "--zmq-url", f"tcp://127.0.0.1:{_free_port()}", "--port", "0"])
    captured = capsys.readouterr()
    assert code == 0
    assert captured.err.count("warning:") == 1
    assert "replay page:" in captured.out
    header, _ = read_replay(out)
    assert header["result"] == "SUCCESS"
    assert header["info"]["tree"] == tree
    assert {n["id"] for n in header["tree"]["nodes"]} >= {"Sequence", "Script", "Sleep"}


def test_the_live_view_keeps_the_robot_in_the_middle() -> None:
    world = World(ROOM, seed=3)
    tree = DriveTree(world)
    live = LiveViewer(world, tree, LiveOptions(port=None, max_fps=1e6), say=lambda s: None)
    shifts: list[list[float]] = []
    try:
        assert live.start() and live.link is not None
        send_many = live.link.send_many

        def spy(commands: list[dict[str, Any]]) -> None:
            shifts.extend(c["matrix"] for c in commands
                          if c["type"] == "set_transform" and c["path"] == "/meshcat")
            send_many(commands)

        live.link.send_many = spy  # type: ignore[method-assign]
        start = world.robots["husky"].base_pose2d()[:2]
        report = Runner(tree, world, RunOptions(), on_tick=[live]).run()
        assert report.status == "SUCCESS"
        end = world.robots["husky"].base_pose2d()[:2]
    finally:
        live.close()
        world.close()
    assert len(shifts) > 20  # re-centred again and again while it drove
    last = shifts[-1]  # column-major 4x4: the translation is elements 12, 13
    assert [-last[12], -last[13]] == pytest.approx(list(end), abs=0.006)
    assert np.hypot(end[0] - start[0], end[1] - start[1]) > 1.0


def test_a_body_that_comes_and_goes_within_one_tick_breaks_nothing(tmp_path: Path) -> None:
    from bt_manip.sim.world_spec import BodySpec, Part, Pose3D, Range2D
    from bt_manip.viz.recorder import Recorder

    spec = BodySpec(
        name="blink", movable=True, parts=[Part("box", (0.2, 0.2, 0.2))], urdf=None,
        pose=Pose3D((-1.5, 1.5, 0.3)), planar=False, mass=1.0, friction=0.8,
        colour=(0.5, 0.3, 0.1, 1.0), randomize=Range2D(), line=0,
    )

    def blink(runner: Any) -> None:
        if runner.ticks == 5:  # spawned and deleted by one tick (a Sequence of both)
            runner.world.spawn(spec)
            runner.world.remove("blink")

    world = World(ROOM, seed=3)
    tree = DriveTree(world)
    live = LiveViewer(world, tree, LiveOptions(port=None, max_fps=1e6, keep_serving=True),
                      say=lambda s: None)
    recorder = Recorder(tmp_path / "r.html", world, tree)
    try:
        assert live.start()
        report = Runner(tree, world, RunOptions(), on_tick=[blink, live, recorder]).run()
        assert report.status == "SUCCESS" and live.active
        assert "blink" not in live.scene.bodies  # type: ignore[union-attr]
    finally:
        recorder.close()
        live.stop()
        world.close()
    header, _ = read_replay(tmp_path / "r.html")
    assert "blink" not in {b["name"] for b in header["scene"]["bodies"]}  # never in a frame
