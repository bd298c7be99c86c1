"""The pages in a real browser (headless Chromium): scene drawn, robot moves, statuses change.

Skipped, with the reason, where no Chromium is installed. (The README's screenshot is made by
``docs/make_screenshot.py`` from a Scenario A replay.)
"""

from __future__ import annotations

import io
import threading
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from drive_tree import ROOM, DriveTree

from bt_manip.cli import main
from bt_manip.run.runner import Runner, RunOptions
from bt_manip.sim.world import World
from bt_manip.viz.live import LiveOptions, LiveViewer
from bt_manip.viz.recorder import Recorder
from bt_manip.viz.replay_page import read_replay

pytestmark = pytest.mark.browser
REPO = Path(__file__).resolve().parents[2]
HERE = Path(__file__).resolve().parent
TABLE = REPO / "worlds" / "sawyer_table.yaml"
SCENE = "/meshcat/bt_manip"
VIEWPORT = {"width": 1200, "height": 700}
VIEW_BOX = (0, 0, 800, 640)  # the 3D view: left of the 380 px tree panel, above the timeline


def _image(png: bytes) -> np.ndarray:
    from PIL import Image

    return np.asarray(Image.open(io.BytesIO(png)).convert("RGB")).astype(int)


def _view(img: np.ndarray) -> np.ndarray:
    x0, y0, x1, y1 = VIEW_BOX
    return img[y0:y1, x0:x1]


def _husky_yellow(img: np.ndarray) -> int:
    """Pixels of the Husky's yellow top plate (URDF colour 0.8 0.8 0, shaded)."""
    r, g, b = img[..., 0], img[..., 1], img[..., 2]
    return int(np.count_nonzero((r > 110) & (g > 110) & (b < 60) & (abs(r - g) < 40)))


def _assert_scene_drawn(img: np.ndarray) -> None:
    view = _view(img)
    assert view.std() > 20, "the 3D view is blank"
    assert len(np.unique(view.reshape(-1, 3) // 16, axis=0)) > 40, "the 3D view is flat"
    assert _husky_yellow(view) > 200, "the robot's colours are not in the 3D view"


def _statuses(page: Any) -> dict[str, str]:
    return page.evaluate(
        "Object.fromEntries([...document.querySelectorAll('.node')].map("
        "n => [n.querySelector('.name').textContent, n.dataset.status]))"
    )


def test_replay_page_plays_offline(browser: Any, tmp_path: Path) -> None:
    page_file = tmp_path / "replay.html"
    world = World(ROOM, seed=3)
    tree = DriveTree(world, drive_s=3.0)
    recorder = Recorder(page_file, world, tree)
    Runner(tree, world, RunOptions(), on_tick=[recorder]).run()
    recorder.close()
    world.close()

    page = browser.new_page(viewport=VIEWPORT)
    requests: list[str] = []
    page.on("request", lambda r: requests.append(r.url))
    errors: list[str] = []
    page.on("pageerror", lambda e: errors.append(str(e)))
    page.goto(page_file.as_uri())
    page.wait_for_function("window.btReplay !== undefined", timeout=30000)
    assert page.evaluate("btReplay.error") is None
    assert page.evaluate("btReplay.frames") > 100
    page.uncheck("#follow")  # fixed camera: the robot moves across the view

    page.evaluate("btReplay.seek(0)")
    page.wait_for_timeout(300)
    start = _image(page.screenshot())
    at_start = _statuses(page)
    page.evaluate("btReplay.seek(1.5)")
    page.wait_for_timeout(300)
    during = _statuses(page)
    page.evaluate("btReplay.seek(btReplay.duration)")
    page.wait_for_timeout(300)
    end = _image(page.screenshot())
    at_end = _statuses(page)

    assert not errors, errors
    assert all(u.startswith("file://") or u.startswith("data:") for u in requests), requests
    _assert_scene_drawn(start)
    _assert_scene_drawn(end)
    changed = np.abs(_view(start) - _view(end)).sum(axis=2) > 60
    assert changed.mean() > 0.01, "start and end frames look the same though the robot drove"
    assert at_start["drive"] == "RUNNING" and at_start["turn"] == "IDLE"
    assert during["drive"] == "RUNNING"
    assert at_end["drive"] == "SUCCESS" and at_end["mission"] == "SUCCESS"
    assert "result: SUCCESS" in page.inner_text("#result")
    assert "doorway is blocked" in page.inner_text("#details")  # the failure stays listed

    # late in the run, following the robot: the failure listed once
    page.check("#follow")
    page.mouse.move(10, 10)
    page.evaluate("btReplay.seek(4.7)")
    page.wait_for_timeout(300)
    assert page.inner_text("#details").count("plan_a") == 1
    assert _statuses(page)["plan_a"] == "FAILURE"  # it failed: red, not IDLE
    _assert_scene_drawn(_image(page.screenshot()))
    page.close()


def test_live_page_follows_the_run(browser: Any) -> None:
    world = World(ROOM, seed=3)
    tree = DriveTree(world, drive_s=3.5)
    # kept serving after the run (as --keep-serving does): the page is read to the end
    live = LiveViewer(world, tree, LiveOptions(port=0, keep_serving=True), say=lambda s: None)
    assert live.start()
    go = threading.Event()
    done = threading.Event()

    def run() -> None:
        go.wait(30)
        Runner(tree, world, RunOptions(realtime=1.0), on_tick=[live]).run()
        done.set()

    thread = threading.Thread(target=run, daemon=True)
    thread.start()
    page = browser.new_page(viewport=VIEWPORT)
    try:
        assert live.page is not None
        page.goto(live.page.url)
        page.wait_for_selector(".node", timeout=20000)
        page.frame_locator("#meshcat-frame").locator("canvas").wait_for(timeout=20000)
        page.wait_for_timeout(1500)  # the meshcat view receives the scene
        before = _image(page.screenshot())
        first = _statuses(page)
        go.set()
        seen = [first]
        # read the page until it shows the drive running, before the screenshot (slow on a busy
        # machine: taken first, it could last longer than the drive)
        while not done.is_set() and seen[-1]["drive"] != "RUNNING":
            page.wait_for_timeout(100)
            seen.append(_statuses(page))
        middle = _image(page.screenshot())
        while not done.is_set():
            page.wait_for_timeout(250)
            seen.append(_statuses(page))
        # the page polls a few times a second; on a loaded machine give it time to catch up
        for _ in range(40):
            seen.append(_statuses(page))
            if seen[-1]["mission"] == "SUCCESS":
                break
            page.wait_for_timeout(250)
        page.wait_for_timeout(600)
        after = _image(page.screenshot())
    finally:
        go.set()
        thread.join(30)
        page.close()
        live.stop()
        world.close()

    assert first["mission"] == "IDLE"
    drive_states = [s["drive"] for s in seen]
    assert "RUNNING" in drive_states and drive_states[-1] == "SUCCESS"
    assert seen[-1]["mission"] == "SUCCESS"
    _assert_scene_drawn(before)
    _assert_scene_drawn(middle)
    moved = np.abs(_view(before) - _view(after)).sum(axis=2) > 60
    assert moved.mean() > 0.01, "the live view did not change while the robot drove"


_WORLD_POSITION = """([path, t]) => {
  btReplay.seek(t);
  const node = btReplay.viewer.scene_tree.find(path.split("/").filter((p) => p)).object;
  const p = node.getWorldPosition(node.position.clone());
  return [p.x, p.y, p.z];
}"""
_MESHES = """(path) => {
  let n = 0;
  btReplay.viewer.scene_tree.find(path.split("/").filter((p) => p)).object.traverse(
    (o) => { if (o.isMesh) n++; });
  return n;
}"""


def _node_times(header: dict[str, Any], name: str, code: int) -> list[float]:
    """Times at which the node ``name`` turned to status ``code`` in a replay."""
    names = [n["name"] for n in header["tree"]["nodes"]]
    i = names.index(name)
    return [t for t, j, c, _ in header["tree"]["events"] if j == i and c == code]


def test_replay_shows_spawned_blocks_moving_with_the_gripper(
    browser: Any, tmp_path: Path
) -> None:
    page_file = tmp_path / "blocks.html"
    tree = str(HERE / "viz_blocks.xml")
    assert main(["run", tree, "--world", str(TABLE), "--quiet", "--record", str(page_file)]) == 0
    header, _ = read_replay(page_file)
    (grasped,) = _node_times(header, "grasp", 2)
    (releasing,) = _node_times(header, "release", 1)
    (deleted,) = _node_times(header, "delete_1", 2)
    assert grasped < deleted < releasing

    page = browser.new_page(viewport=VIEWPORT)
    errors: list[str] = []
    page.on("pageerror", lambda e: errors.append(str(e)))
    page.goto(page_file.as_uri())
    page.wait_for_function("window.btReplay !== undefined", timeout=30000)
    assert page.evaluate("btReplay.error") is None
    bodies = {b["name"]: b for b in page.evaluate("btReplay.bodies()")}
    # spawned by the tree's first tick, at sim time 0; block_1 deleted on the way
    assert bodies["block_0"]["appear"] == 0.0 and bodies["block_0"]["disappear"] is None
    assert bodies["block_1"]["appear"] == 0.0
    assert bodies["block_1"]["disappear"] == pytest.approx(deleted, abs=1e-6)
    assert page.evaluate(_MESHES, f"{SCENE}/block_0") == 1  # drawn: one box each
    assert page.evaluate(_MESHES, f"{SCENE}/block_1") == 1

    # while carried, the block stays between the fingers as the gripper moves
    left, right = f"{SCENE}/sawyer/gripper_left_finger", f"{SCENE}/sawyer/gripper_right_finger"
    carried = []
    for t in np.linspace(grasped + 0.2, releasing, 8):
        block = np.array(page.evaluate(_WORLD_POSITION, [f"{SCENE}/block_0", t]))
        fingers = (np.array(page.evaluate(_WORLD_POSITION, [left, t]))
                   + np.array(page.evaluate(_WORLD_POSITION, [right, t]))) / 2
        carried.append((block, block - fingers))
    travel = np.linalg.norm(carried[-1][0] - carried[0][0])
    grip = np.array([offset for _, offset in carried])
    assert travel > 0.2, f"the block moved only {travel:.3f} m while carried"
    assert np.linalg.norm(grip - grip[0], axis=1).max() < 0.01, grip
    assert np.linalg.norm(grip[0]) < 0.06  # and it is at the fingers, not elsewhere

    # the replay's own positions agree with the drawn ones; the block ends in the bin
    start = page.evaluate("btReplay.bodyPosition('block_0', 0)")
    assert start == pytest.approx([0.7, 0.0, 0.7725], abs=0.011)
    end = page.evaluate("btReplay.bodyPosition('block_0', btReplay.duration)")
    assert abs(end[0] - 0.75) < 0.13 and abs(end[1] + 0.25) < 0.13 and end[2] < 0.8
    # block_1 is shown before its deletion and hidden after it, also when seeking back
    for t, shown in ((deleted - 0.1, True), (deleted + 0.1, False), (0.0, True)):
        page.evaluate(f"btReplay.seek({t})")
        assert page.evaluate("btReplay.visible('block_1')") is shown, t
        assert page.evaluate(f"btReplay.bodyPosition('block_1', {t}) !== null") is shown
    assert not errors, errors
    page.close()


_LIVE_POSITION = """(path) => {
  // in the frame of /meshcat: the world's frame (z up), before the view's follow shift
  const root = viewer.scene_tree.find(["meshcat"]).object;
  const node = viewer.scene_tree.find(path.split("/").filter((p) => p)).object;
  const p = root.worldToLocal(node.getWorldPosition(node.position.clone()));
  return [p.x, p.y, p.z];
}"""


_LIVE_MESHES = """(path) => {
  let n = 0;
  viewer.scene_tree.find(path.split("/").filter((p) => p)).object.traverse(
    (o) => { if (o.isMesh) n++; });
  return n;
}"""


def test_live_view_shows_spawned_blocks_moving_with_the_gripper(browser: Any) -> None:
    from bt_manip.episode import Episode, EpisodeSpec

    stops_wanted = 4
    episode = Episode(EpisodeSpec(tree=str(HERE / "viz_blocks.xml"), world=str(TABLE)))
    world = episode.world
    live = LiveViewer(world, episode.tree, LiveOptions(port=0, max_fps=1e6, keep_serving=True),
                      say=lambda s: None)
    assert live.start()
    paused = threading.Event()
    resume = threading.Event()
    stops: list[float] = []

    def pause_while_carrying(runner: Any) -> None:
        # hold the run at a few ticks of the carry, so the browser can be read at rest
        names = {r.name: r for r in episode.tree.node_records()}
        moving = names["lift"].status == "RUNNING" or names["over_bin"].status == "RUNNING"
        if moving and runner.ticks % 4 == 0 and len(stops) < stops_wanted and "abort" not in holder:
            stops.append(world.time)
            truth = world.body_pose("block_0").xyz
            holder["truth"] = np.array(truth)
            paused.set()
            resume.wait(30)
            resume.clear()

    holder: dict[str, Any] = {}
    done = threading.Event()

    def run() -> None:
        try:
            episode.run([live, pause_while_carrying])
        finally:
            done.set()
            paused.set()

    page = browser.new_page(viewport=VIEWPORT)
    thread = threading.Thread(target=run, daemon=True)
    try:
        assert live.page is not None
        page.goto(live.page.url)
        page.frame_locator("#meshcat-frame").locator("canvas").wait_for(timeout=20000)
        meshcat = next(f for f in page.frames if f != page.main_frame)
        page.wait_for_timeout(1000)
        thread.start()
        samples = []
        while True:
            assert paused.wait(60), "the run did not reach the carry"
            paused.clear()
            if done.is_set():
                break
            truth = holder["truth"]
            for _ in range(50):  # until the websocket has delivered the poses of this tick
                block = np.array(meshcat.evaluate(_LIVE_POSITION, f"{SCENE}/block_0"))
                if np.linalg.norm(block - truth) < 1e-3:
                    break
                page.wait_for_timeout(100)
            assert np.linalg.norm(block - truth) < 1e-3, (block, truth)
            fingers = [np.array(meshcat.evaluate(_LIVE_POSITION, f"{SCENE}/sawyer/{f}"))
                       for f in ("gripper_left_finger", "gripper_right_finger")]
            samples.append((block, block - (fingers[0] + fingers[1]) / 2))
            if len(samples) == 1:  # block_1 is still there (deleted after the lift)
                drawn_before = meshcat.evaluate(_LIVE_MESHES, f"{SCENE}/block_1")
            resume.set()
            if len(samples) == stops_wanted:
                break
        resume.set()
        assert done.wait(60)
        # block_1 was deleted on the way: no longer in the view
        gone = meshcat.evaluate(
            "() => viewer.scene_tree.find(['meshcat', 'bt_manip']).children.block_1 === undefined"
        )
    finally:
        holder["abort"] = True
        resume.set()
        thread.join(60)
        page.close()
        live.stop()
        episode.close()
    assert len(samples) == stops_wanted
    positions = np.array([p for p, _ in samples])
    offsets = np.array([o for _, o in samples])
    assert np.linalg.norm(positions[-1] - positions[0]) > 0.1  # the block moved
    assert np.linalg.norm(offsets - offsets[0], axis=1).max() < 0.01  # with the fingers
    assert np.linalg.norm(offsets[0]) < 0.06  # between them
    assert drawn_before == 1 and gone


DEEP_FAILURE = """<root BTCPP_format="4"><BehaviorTree ID="M">
  <Sequence name="carry_wall_panel_to_the_goal_in_the_living_room">
    <Fallback name="carry_or_back_off_and_try_again_from_where_it_stands">
      <AlwaysFailure name="carry_to_goal_through_the_narrow_doorway_of_the_kitchen"
                     _onFailure="why := 'x'"/>
      <Sequence name="clear_and_retry_after_backing_up_half_a_metre">
        <Sleep name="back_up" msec="20"/>
        <AlwaysFailure name="carry_failed_for_good_after_every_retry_of_the_route"/>
      </Sequence>
    </Fallback>
  </Sequence>
</BehaviorTree></root>"""


def test_failed_leaves_stay_red_and_long_failure_lines_wrap(browser: Any, tmp_path: Path) -> None:
    from bt_manip.bt import load_tree_string

    tree = load_tree_string(DEEP_FAILURE)
    page_file = tmp_path / "fail.html"
    recorder = Recorder(page_file, None, tree)
    report = Runner(tree, None, RunOptions(tick_hz=200), on_tick=[recorder]).run()
    recorder.close()
    assert report.status == "FAILURE"
    page = browser.new_page(viewport=VIEWPORT)
    page.goto(page_file.as_uri())
    page.wait_for_function("window.btReplay !== undefined", timeout=30000)
    page.evaluate("btReplay.seek(btReplay.duration)")
    shown = _statuses(page)
    assert set(shown.values()) == {"FAILURE"} | ({"SUCCESS"} if "back_up" in shown else set())
    assert shown["carry_to_goal_through_the_narrow_doorway_of_the_kitchen"] == "FAILURE"
    assert shown["carry_failed_for_good_after_every_retry_of_the_route"] == "FAILURE"
    details = page.inner_text("#details")
    assert "carry_failed_for_good_after_every_retry_of_the_route" in details
    overflow = page.evaluate(
        "[...document.querySelectorAll('#details .fail')].map(e => e.scrollWidth - e.clientWidth)"
    )
    assert overflow and max(overflow) <= 0, overflow  # wrapped, not cut off at the edge
    page.close()


def test_replay_tree_shows_each_nodes_ticks_and_dims_nodes_never_ticked(
        browser: Any, tmp_path: Path) -> None:
    from bt_manip.bt import load_tree_string

    tree = load_tree_string(
        '<root BTCPP_format="4"><BehaviorTree ID="Main"><Fallback name="choose">'
        '<AlwaysSuccess name="first"/><AlwaysSuccess name="second"/>'
        "</Fallback></BehaviorTree></root>")
    page_file = tmp_path / "cov.html"
    recorder = Recorder(page_file, None, tree)
    Runner(tree, None, RunOptions(tick_hz=200), on_tick=[recorder]).run()
    recorder.close()
    page = browser.new_page(viewport=VIEWPORT)
    page.goto(page_file.as_uri())
    page.wait_for_function("window.btReplay !== undefined", timeout=30000)
    badges = page.evaluate(
        "[...document.querySelectorAll('#tree .node')].map(r => [r.querySelector('.name')"
        ".textContent, r.querySelector('.cov').textContent, r.classList.contains('never')])")
    assert badges == [["choose", "\u00d71", False], ["first", "\u00d71", False],
                      ["second", "never ticked", True]]
    page.close()
