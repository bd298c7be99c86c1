"""DropPoint: drop points on a grid over a region of the world; ObjectInRegion on the same
region; the top-down grasp turned by a block's yaw folded into +-45 deg."""

from __future__ import annotations

import math
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pybullet as pb
import pytest
from bhelpers import ROOT, reasons, run_xml

from bt_manip.behaviours.regions import region_of
from bt_manip.sim.world import World

RIM = 0.8675
"""Top of the bin's walls in sawyer_table.yaml (z)."""


@pytest.fixture
def moved_bin() -> Iterator[World]:
    with World(ROOT / "worlds" / "sawyer_table_bin_moved.yaml", seed=0) as world:
        yield world


def _points(world: World, extra: str = "") -> list[np.ndarray]:
    nodes = "".join(
        f'<DropPoint region="bin" index="{i}" point="{{p{i}}}"{extra}/>' for i in range(9)
    )
    report, tree = run_xml(world, f"<Sequence>{nodes}</Sequence>")
    assert report.status == "SUCCESS", report.reason
    bb = tree.blackboard.as_dict()
    return [np.asarray(bb[f"p{i}"], dtype=float) for i in range(9)]


def test_drop_points_are_a_grid_inside_the_bin_opening(table: World) -> None:
    points = _points(table, ' clearance="0.05" margin="0.02"')
    lo, hi = pb.getAABB(table.body_id("bin"), physicsClientId=table.client)
    for p in points:
        # inside the walls (1 cm thick) with the 2 cm margin, 5 cm above the rim
        assert lo[0] + 0.02 < p[0] < hi[0] - 0.02 and lo[1] + 0.02 < p[1] < hi[1] - 0.02
        assert p[2] == pytest.approx(RIM + 0.05, abs=1e-6)
    grid = np.array(points)[:, :2].reshape(3, 3, 2)  # [row][col]
    # columns along x, rows along y, counted from the lowest x and y; 0.24 m / 3 = 8 cm apart
    assert grid[0, 0] == pytest.approx([0.67, -0.33], abs=1e-6)
    assert np.allclose(np.diff(grid[:, :, 0], axis=1), 0.08)
    assert np.allclose(np.diff(grid[:, :, 1], axis=0), 0.08)
    assert np.allclose(np.diff(grid[:, :, 1], axis=1), 0.0)
    assert grid[1, 1] == pytest.approx([0.75, -0.25], abs=1e-6)  # the bin's centre


def test_drop_points_turn_with_a_turned_bin(moved_bin: World) -> None:
    points = _points(moved_bin)
    region = region_of(moved_bin, "bin")
    pos, quat = pb.getBasePositionAndOrientation(
        moved_bin.body_id("bin"), physicsClientId=moved_bin.client
    )
    yaw = pb.getEulerFromQuaternion(quat)[2]
    assert yaw == pytest.approx(math.radians(20), abs=1e-4)
    turn = np.array([[math.cos(yaw), math.sin(yaw)], [-math.sin(yaw), math.cos(yaw)]])
    local = np.array([turn @ (p[:2] - np.asarray(pos[:2])) for p in points])
    # in the bin's own frame: the same 3 x 3 grid of 8 cm cells as for an unturned bin
    expected = [(x, y) for y in (-0.08, 0.0, 0.08) for x in (-0.08, 0.0, 0.08)]
    assert np.allclose(local, expected, atol=1e-6)
    for p in points:
        assert region.contains(p - [0.0, 0.0, 0.07])  # straight below, between the walls
        assert p[2] == pytest.approx(RIM + 0.06, abs=1e-6)


def test_object_in_region_uses_the_turned_bin_not_its_bounding_box(moved_bin: World) -> None:
    # a block on the table inside the bin's world bounding box, outside the turned bin, and
    # one spawned above a drop point, which falls into the bin
    report, tree = run_xml(
        moved_bin,
        "<Sequence>"
        '<SpawnModel model="outside" size="0.05;0.05;0.05" pose="0.69;-0.42;0.7725;0"/>'
        '<DropPoint region="bin" index="4" clearance="0.03" point="{p}"/>'
        '<SpawnModel model="dropped" size="0.05;0.05;0.05" pose="0.84;-0.27;0.9;0.3"/>'
        '<Sleep msec="1500"/>'
        '<ObjectInRegion name="dropped_in" object="dropped" inside="bin"/>'
        '<Inverter><ObjectInRegion name="outside_in" object="outside" inside="bin"/></Inverter>'
        "</Sequence>",
    )
    assert report.status == "SUCCESS", report.reason
    assert reasons(report)["outside_in"].startswith("'outside' at (0.690, -0.420, 0.772)")
    lo, hi = pb.getAABB(moved_bin.body_id("bin"), physicsClientId=moved_bin.client)
    outside = pb.getBasePositionAndOrientation(
        moved_bin.movable["outside"], physicsClientId=moved_bin.client
    )[0]
    assert all(lo[i] <= outside[i] <= hi[i] for i in range(3))
    assert tree.blackboard.as_dict()["p"][:2] == pytest.approx([0.84, -0.27], abs=1e-6)


def test_index_outside_the_grid_fails_with_the_reason(table: World) -> None:
    report, _ = run_xml(table, '<DropPoint region="bin" index="9" point="{p}"/>')
    assert report.status == "FAILURE"
    assert reasons(report)["DropPoint"] == (
        "index 9 is not a cell of the 3 x 3 grid over 'bin' (0..8)"
    )
    report, tree = run_xml(
        table,
        '<Sequence><Script code="i := 7"/>'
        '<DropPoint region="bin" index="{i}" rows="2" cols="4" point="{p}"/></Sequence>',
    )
    assert report.status == "SUCCESS", report.reason
    assert tree.blackboard.as_dict()["p"][:2] == pytest.approx([0.84, -0.19], abs=1e-6)  # 6 x 12 cm
    report, _ = run_xml(
        table,
        '<Sequence><Script code="i := 8"/>'
        '<DropPoint region="bin" index="{i}" rows="2" cols="4" point="{p}"/></Sequence>',
    )
    assert reasons(report)["DropPoint"] == (
        "index 8 is not a cell of the 2 x 4 grid over 'bin' (0..7)"
    )
    report, _ = run_xml(
        table,
        '<Sequence><Script code="i := -1"/>'
        '<DropPoint region="bin" index="{i}" point="{p}"/></Sequence>',
    )
    assert reasons(report)["DropPoint"] == (
        "DropPoint (line 1): input port 'index' (entry 'i'): must be >= 0, got -1.0"
    )
    report, _ = run_xml(
        table,
        '<Sequence><Script code="i := 2.5"/>'
        '<DropPoint region="bin" index="{i}" point="{p}"/></Sequence>',
    )
    assert reasons(report)["DropPoint"] == "index must be a whole number, got 2.5"
    report, _ = run_xml(table, '<DropPoint region="bin" index="0" margin="0.2" point="{p}"/>')
    assert reasons(report)["DropPoint"] == (
        "margin 0.2 m leaves no room inside 'bin' (0.280 x 0.280 m)"
    )


def test_unknown_region_fails_with_the_known_bodies(table: World) -> None:
    report, tree = run_xml(table, '<DropPoint region="bni" index="0" point="{p}"/>')
    assert report.status == "FAILURE"
    assert reasons(report)["DropPoint"] == (
        "no body named 'bni' in sawyer_table.yaml (did you mean 'bin'?); "
        "bodies: bin, cafe_table, ground, sawyer"
    )
    assert "p" not in tree.blackboard.as_dict()
    report, _ = run_xml(
        table, '<Sequence><SpawnModel model="block_0"/>'
        '<ObjectInRegion object="block_0" inside="bni"/></Sequence>'
    )
    assert report.status == "FAILURE"
    assert reasons(report)["ObjectInRegion"].startswith("no body named 'bni' in sawyer_table")


def test_drop_point_literals_a_port_cannot_take_are_errors_of_the_tree(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from bt_manip.cli import main

    tree = tmp_path / "drop.xml"
    tree.write_text(
        '<root BTCPP_format="4"><BehaviorTree ID="Main"><Sequence>\n'
        '<DropPoint region="bin" index="-1" rows="0" clearance="3" point="{p}"/>\n'
        "</Sequence></BehaviorTree></root>\n"
    )
    assert main(["validate", str(tree)]) == 2
    err = capsys.readouterr().err.splitlines()
    bad = f"{tree}:2: bad value for port '{{}}' of DropPoint: {{}}"
    assert err == [
        bad.format("index", "must be >= 0, got -1"),
        bad.format("rows", "must be in [1, 100], got 0"),
        bad.format("clearance", "must be in [0, 2], got 3"),
    ]


@pytest.mark.parametrize(
    ("block_deg", "turn_deg"),
    [(40.0, 40.0), (-40.0, -40.0), (80.0, -10.0), (-130.0, -40.0)],
)
def test_top_down_grasp_turns_by_the_block_yaw_folded_into_45_deg(
    table: World, block_deg: float, turn_deg: float
) -> None:
    """A box looks the same every 90 deg: the gripper turns by the block's yaw folded into
    +-45 deg (80 deg is a turn of -10 deg), closes on two faces and holds the block."""
    robot = table.robots["sawyer"]

    def tool_yaw() -> float:
        x_axis = robot.link_transform("grasp_frame")[:3, 0]
        return math.degrees(math.atan2(x_axis[1], x_axis[0]))

    before = tool_yaw()
    yaw = math.radians(block_deg)
    report, _ = run_xml(
        table,
        "<Sequence>"
        f'<SpawnModel model="b" size="0.05;0.05;0.05" pose="0.7;0.1;0.7725;{yaw}" mass="0.1"/>'
        '<OpenGripper opening="0.075"/>'
        '<MoveToPose object="b" match_object_yaw="true" approach="0.12" path="line"/>'
        '<CloseGripper require_object="true"/><Lift height="0.1"/><IsHolding object="b"/>'
        "</Sequence>",
    )
    assert report.status == "SUCCESS", report.reason
    turned = (tool_yaw() - before + 180.0) % 360.0 - 180.0
    assert turned == pytest.approx(turn_deg, abs=2.0)
    lo, _ = pb.getAABB(table.movable["b"], physicsClientId=table.client)
    assert lo[2] > 0.7475 + 0.05  # lifted off the table by the fingers


def test_region_of_furniture_and_of_a_robot(table: World) -> None:
    # the cafe table (boxes and a cylinder): one cell over all of it is its top's centre
    report, tree = run_xml(
        table,
        '<DropPoint region="cafe_table" index="0" rows="1" cols="1" margin="0" clearance="0"'
        ' point="{p}"/>',
    )
    assert report.status == "SUCCESS", report.reason
    assert tree.blackboard.as_dict()["p"] == pytest.approx([1.0, 0.0, 0.7475], abs=1e-6)
    # a body with links (the robot): the world bounding box of all its links, the gripper's
    # included
    robot = table.robots["sawyer"]
    region = region_of(table, "sawyer")
    assert np.allclose(region.pose, np.eye(4))
    assert region.contains(robot.link_transform("grasp_frame")[:3, 3])
    assert not region.contains(np.array([0.75, -0.25, 0.8]))  # the bin's centre
