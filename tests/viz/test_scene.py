"""The world as a meshcat scene: URDF visuals, colours, frames that match PyBullet's."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from bt_manip.overlay import FrameItem, Overlay, PathItem
from bt_manip.sim.compose import composed_urdf
from bt_manip.sim.world import World
from bt_manip.viz.overlay import item_json
from bt_manip.viz.scene import ROOT, build_scene, row_matrix
from bt_manip.viz.urdf_visuals import origin_matrix, read_visuals

REPO = Path(__file__).resolve().parents[2]


def test_urdf_visuals_of_the_husky_ur3(room: World) -> None:
    visuals = read_visuals(composed_urdf(room.robots["husky"].description))
    by_link = {v.link: v for v in visuals}
    top = by_link["top_plate_link"]
    assert top.kind == "mesh" and top.mesh is not None and top.mesh.suffix == ".stl"
    assert top.rgba == pytest.approx((0.8, 0.8, 0.0, 1.0))  # the URDF's named material Yellow
    shoulder = by_link["ur3_shoulder_link"]
    assert shoulder.mesh is not None and shoulder.mesh.suffix == ".dae"
    assert shoulder.rgba is None  # no URDF material: the .dae keeps its own colours
    finger = by_link["gripper_left_finger"]
    assert finger.kind == "box" and finger.size == pytest.approx((0.03, 0.012, 0.07))
    assert finger.origin[:3, 3] == pytest.approx([0.0, 0.006, 0.035])


def test_origin_matrix_follows_urdf_rpy() -> None:
    m = origin_matrix((1, 2, 3), (0.0, 0.0, np.pi / 2))
    assert m[:3, 3] == pytest.approx([1, 2, 3])
    assert m[:3, :3] @ np.array([1.0, 0, 0]) == pytest.approx([0, 1, 0], abs=1e-12)
    m = origin_matrix((0, 0, 0), (np.pi / 2, 0.0, 0.0))
    assert m[:3, :3] @ np.array([0, 1.0, 0]) == pytest.approx([0, 0, 1], abs=1e-12)


def test_link_frames_match_pybullet(room: World) -> None:
    robot = room.robots["husky"]
    robot.set_base_twist(0.5, 0.4)
    room.step(120)
    scene = build_scene(room)
    poses = scene.read_poses()
    base = row_matrix(poses[scene.tracks.index(f"{ROOT}/husky")])
    checked = 0
    for k, path in enumerate(scene.tracks):
        parts = path.split("/")
        if len(parts) == 5 and parts[3] == "husky":
            world_pose = base @ row_matrix(poses[k])
            assert world_pose == pytest.approx(robot.link_transform(parts[4]), abs=1e-6), path
            checked += 1
    assert checked >= 15  # wheels, plate, arm links, gripper


def test_world_bodies_and_colours(room: World) -> None:
    scene = build_scene(room)
    paths = {o.path: o for o in scene.objects}
    assert f"{ROOT}/husky/top_plate_link/v0" in paths
    assert paths[f"{ROOT}/crate/v0"].rgba == pytest.approx((0.2, 0.35, 0.85, 1.0))  # blue
    assert paths[f"{ROOT}/table/v0"].rgba == pytest.approx((0.7, 0.52, 0.33, 1.0))  # wood
    # the north wall has a door: two boxes
    assert f"{ROOT}/north/v1" in paths and f"{ROOT}/north/v2" not in paths
    static = dict(scene.static)
    assert f"{ROOT}/table" in static and f"{ROOT}/crate" not in static
    assert f"{ROOT}/crate" in scene.tracks
    meshes = scene.mesh_files()
    assert len(meshes) == len(set(meshes)) and any(m.name == "wheel.stl" for m in meshes)


def test_parts_keep_their_own_colours() -> None:
    with World(REPO / "worlds" / "sawyer_table.yaml") as world:
        scene = build_scene(world)
        table = [scene.objects[k] for k in scene.body_objects["cafe_table"]]
        assert len(table) == 3
        assert table[0].rgba == pytest.approx((0.7, 0.52, 0.33, 1.0))  # wood top
        assert table[2].rgba == pytest.approx((0.3, 0.3, 0.3, 1.0))  # dark_grey foot
        # the Sawyer is drawn from its URDF primitives in its red
        sawyer = [scene.objects[k] for k in scene.body_objects["sawyer"]]
        assert any(o.rgba == pytest.approx((0.72, 0.08, 0.08, 1.0)) for o in sawyer)


def test_overlay_keeps_the_latest_item_per_name() -> None:
    overlay = Overlay()
    overlay.show_path("plan", [(0, 0), (1, 0), (1, 1)])
    overlay.show_frame("goal", np.eye(4))
    v = overlay.version
    overlay.show_path("plan", [(0, 0), (2, 0)])
    assert overlay.version == v + 1
    item = overlay.items["plan"]
    assert isinstance(item, PathItem) and item.points.shape == (2, 3)
    assert item.points[:, 2] == pytest.approx([0.03, 0.03])
    overlay.show_path("plan", [(0, 0)])  # fewer than two points: nothing to draw
    assert "plan" not in overlay.items
    overlay.clear()
    assert not overlay.items
    with pytest.raises(ValueError, match="4x4"):
        overlay.show_frame("bad", np.eye(3))
    triad = item_json(FrameItem(np.eye(4), 0.2))
    assert triad["object"]["type"] == "LineSegments"
    assert max(triad["geometries"][0]["data"]["attributes"]["position"]["array"]) == 0.2


def test_each_run_has_its_own_overlay_and_viewers_find_it(room: World) -> None:
    from bt_manip.bt import Tree, TreeContext
    from bt_manip.bt.leaves import AlwaysSuccess
    from bt_manip.run.context import RunContext, run_overlay

    first, second = RunContext.for_world(room), RunContext.for_world(room)
    first.overlay.show_path("plan", [(0, 0), (1, 0)])
    assert "plan" not in second.overlay.items  # nothing of a run is kept on the world
    assert run_overlay(Tree(AlwaysSuccess(), context=first)) is first.overlay
    assert run_overlay(Tree(AlwaysSuccess(), context=TreeContext())) is None
