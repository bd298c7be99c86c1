"""DropPoint with a robot: the cell its arm reaches (the asked one, else the nearest one, else
one reached with the tool tilted within ``max_tilt``), and without a robot the cell as asked."""

from __future__ import annotations

import math
from collections.abc import Iterator

import numpy as np
import pytest
from bhelpers import ROOT, reasons, run_xml

from bt_manip.behaviours.regions import grid_cell, region_of
from bt_manip.geometry import pose_matrix
from bt_manip.manipulation import cartesian
from bt_manip.run.context import RunContext
from bt_manip.sim.world import World

CLEARANCE = 0.0625
"""The drop height of Scenario B's tree (m above the rim)."""


@pytest.fixture
def far_bin() -> Iterator[World]:
    with World(ROOT / "worlds" / "sawyer_table_bin_far.yaml", seed=0) as world:
        yield world


def _drop(world: World, attributes: str, before: str = "", region: str = "bin"
          ) -> tuple[str, dict[str, object], str]:
    """Runs one DropPoint over ``region`` (after ``before``): its status, the blackboard, its
    reason."""
    report, tree = run_xml(
        world,
        f"<Sequence>{before}<DropPoint name=\"drop\" region=\"{region}\" point=\"{{p}}\" "
        f"tool_orientation=\"{{o}}\" cell=\"{{c}}\" tilt=\"{{t}}\" {attributes}/></Sequence>",
    )
    return report.status, tree.blackboard.as_dict(), reasons(report).get("drop", "")


def _reaches(world: World, point: list[float], quat: list[float]) -> bool:
    """Whether the Sawyer's grasp frame reaches ``point`` with the tool at ``quat`` (IK from
    the arm's joints now)."""
    robot = world.robots["sawyer"]
    services = RunContext.for_world(world).robot_services("sawyer")
    try:
        cartesian.solve(services, robot.description.grasp_frame, pose_matrix(point, quat),
                        robot.arm_positions())
    except cartesian.CartesianError:
        return False
    return True


DOWN = [0.0, 1.0, 0.0, 0.0]


def test_a_cell_the_arm_reaches_is_kept_and_the_point_is_the_cell_s_as_without_a_robot(
    far_bin: World,
) -> None:
    status, bb, _ = _drop(far_bin, f'index="4" clearance="{CLEARANCE}" robot="sawyer"')
    assert status == "SUCCESS"
    region = region_of(far_bin, "bin")
    expected = [float(v) for v in grid_cell(region, 4, 3, 3, 0.02, CLEARANCE)]
    assert bb["p"] == expected and bb["c"] == 4 and bb["t"] == 0.0
    assert bb["o"] == DOWN  # the requested orientation itself, for MoveToPose


def test_without_a_robot_the_asked_cell_is_given_even_beyond_reach(far_bin: World) -> None:
    status, bb, _ = _drop(far_bin, f'index="2" clearance="{CLEARANCE}"')
    assert status == "SUCCESS"
    region = region_of(far_bin, "bin")
    assert bb["p"] == [float(v) for v in grid_cell(region, 2, 3, 3, 0.02, CLEARANCE)]
    assert bb["c"] == 2 and bb["t"] == 0.0 and bb["o"] == DOWN
    assert not _reaches(far_bin, bb["p"], DOWN)  # type: ignore[arg-type]


def test_a_cell_beyond_reach_gives_way_to_the_nearest_cell_the_arm_reaches(
    far_bin: World,
) -> None:
    region = region_of(far_bin, "bin")
    cells = [[float(v) for v in grid_cell(region, i, 3, 3, 0.02, CLEARANCE)] for i in range(9)]
    # at the bin's far corner, cells 2 and 5 are out of the top-down reach; cells 1 and 5 are
    # the nearest to cell 2 (8 cm), cells 4 and 8 to cell 5
    assert not _reaches(far_bin, cells[2], DOWN) and not _reaches(far_bin, cells[5], DOWN)
    assert _reaches(far_bin, cells[1], DOWN) and _reaches(far_bin, cells[4], DOWN)
    status, bb, _ = _drop(far_bin, f'index="2" clearance="{CLEARANCE}" robot="sawyer"')
    assert status == "SUCCESS"
    assert bb["c"] == 1 and bb["p"] == cells[1] and bb["t"] == 0.0 and bb["o"] == DOWN
    status, bb, _ = _drop(far_bin, f'index="5" clearance="{CLEARANCE}" robot="sawyer"')
    assert status == "SUCCESS"
    assert bb["c"] == 4 and bb["p"] == cells[4]  # 4 and 8 as near: the lower number


def test_of_cells_equally_near_the_one_with_fewer_objects_in_it_is_taken() -> None:
    with World(ROOT / "worlds" / "sawyer_table_bin_far.yaml", seed=0) as world:
        region = region_of(world, "bin")
        x, y, _ = grid_cell(region, 4, 3, 3, 0.02, CLEARANCE).tolist()
        block = f'<SpawnModel model="lying" size="0.05;0.05;0.05" pose="{x};{y};0.79;0.3"/>'
        status, bb, reason = _drop(world, f'index="5" clearance="{CLEARANCE}" robot="sawyer"',
                                   block)
        assert status == "SUCCESS", reason
        assert bb["c"] == 8  # cell 4 holds a block; cell 8, as near to cell 5, holds none
        # an asked cell the arm reaches is kept, whatever lies in it
        status, bb, _ = _drop(world, f'index="4" clearance="{CLEARANCE}" robot="sawyer"')
        assert status == "SUCCESS" and bb["c"] == 4


PAD = '<SpawnModel model="{name}" size="0.06;0.06;0.01" pose="{x};0.3;0.7525;0"/>'
"""A small pad on the table, its only drop cell at (x, 0.3)."""


def test_no_cell_reached_top_down_tilts_the_tool_within_the_cone(far_bin: World) -> None:
    status, bb, reason = _drop(
        far_bin, 'index="0" rows="1" cols="1" clearance="0.05" robot="sawyer" '
        'max_tilt="30"', PAD.format(name="pad_a", x=1.0), "pad_a",
    )
    assert status == "SUCCESS", reason
    point, quat, tilt = bb["p"], bb["o"], bb["t"]
    assert isinstance(point, list) and isinstance(quat, list) and isinstance(tilt, float)
    assert point[:2] == pytest.approx([1.0, 0.3], abs=1e-6)
    assert 0.0 < tilt <= 30.0
    assert not _reaches(far_bin, point, DOWN)
    assert _reaches(far_bin, point, quat)
    # the tool axis (z of the grasp frame) turned by the tilt from straight down, leaning away
    # from the robot's base (the wrist toward it)
    axis = pose_matrix(point, quat)[:3, 2]
    assert math.degrees(math.acos(-axis[2])) == pytest.approx(tilt, abs=1e-6)
    base = far_bin.robots["sawyer"].link_transform("right_arm_base_link")[:3, 3]
    outward = np.array([point[0] - base[0], point[1] - base[1]])
    assert float(np.dot(axis[:2], outward / np.linalg.norm(outward))) == pytest.approx(
        math.sin(math.radians(tilt)), abs=1e-6)
    # MoveToPose takes the point and the orientation written there
    report, _ = run_xml(
        far_bin,
        '<Sequence><DropPoint region="pad_a" index="0" rows="1" cols="1" clearance="0.05" '
        'robot="sawyer" max_tilt="30" point="{p}" tool_orientation="{o}"/>'
        '<MoveToPose position="{p}" orientation="{o}"/></Sequence>',
    )
    assert report.status == "SUCCESS", report.reason
    robot = far_bin.robots["sawyer"]
    reached = robot.link_transform(robot.description.grasp_frame)
    assert np.linalg.norm(reached[:3, 3] - point) < 0.01
    assert float(reached[:3, 2] @ axis) > math.cos(math.radians(2.0))
    # without room to tilt: FAILURE naming the best IK error met
    status, _, reason = _drop(
        far_bin, 'index="0" rows="1" cols="1" clearance="0.05" robot="sawyer" '
        'max_tilt="0"', region="pad_a",
    )
    assert status == "FAILURE"
    assert reason.startswith(
        "sawyer reaches no cell of the 1 x 1 grid over 'pad_a': no candidate is reached with "
        "the requested orientation: best IK error ")
    assert "mm" in reason and "at cell 0 tilted 0 deg" in reason


def test_a_region_out_of_reach_fails_with_the_best_ik_error(far_bin: World) -> None:
    status, _, reason = _drop(
        far_bin, 'index="0" rows="2" cols="2" clearance="0.05" robot="sawyer"',
        PAD.format(name="pad_b", x=1.25), "pad_b",
    )
    assert status == "FAILURE"
    head = ("sawyer reaches no cell of the 2 x 2 grid over 'pad_b': no candidate is reached "
            "with the tool within 25 deg of the requested orientation: best IK error ")
    assert reason.startswith(head), reason
    error_mm = float(reason[len(head):].split(" mm")[0])
    assert error_mm > 50.0  # far beyond the solver's tolerance: the arm falls short
    assert "tilted 25 deg" in reason  # the largest tilt comes closest
    # a region beyond what the arm can stretch to: IK's own reason
    status, _, reason = _drop(
        far_bin, 'index="0" rows="1" cols="1" robot="sawyer"',
        '<SpawnModel model="pad_c" size="0.06;0.06;0.01" pose="3.0;0.0;0.005;0"/>', "pad_c",
    )
    assert status == "FAILURE"
    assert "at cell 0" not in reason and ": cell 0: beyond reach: target" in reason, reason


def test_an_unknown_robot_fails_with_the_robots_of_the_world(far_bin: World) -> None:
    status, _, reason = _drop(far_bin, 'index="0" robot="panda"')
    assert status == "FAILURE"
    assert reason == "no robot named 'panda'; robots: sawyer"
