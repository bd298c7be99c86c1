"""Arm, gripper and attach behaviours on the real robots, outcomes checked in the world."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pybullet as pb
import pytest
from bhelpers import ROOT, place_robot, reasons, run_xml, sample_every_step

from bt_manip.run.context import RunContext
from bt_manip.sim.world import World

PICK = """<Sequence>
  <OpenGripper/>
  <MoveJointsSequentially name="pregrasp" targets="70;11;78;-56;85;4" order="0;2;3;5;4;1"/>
  <CloseGripper name="close" holding="{holding}" object="{held}"/>
  <Attach name="attach" object="panel"/>
  <Lift name="lift" deltas="0;-50;-30;0;0;0" speed="0.3"/>
  <IsAttached object="panel"/>
  <ObjectAbove object="panel" height="0.1"/>
  <CarriedClear object="panel"/>
</Sequence>"""


def test_scenario_a_pick_and_lift(house_at_pregrasp: World) -> None:
    world = house_at_pregrasp
    report, tree = run_xml(world, PICK)
    assert report.status == "SUCCESS", report.reason
    robot = world.robots["husky"]
    q = np.degrees(robot.arm_positions())
    assert q == pytest.approx([70, -39, 48, -56, 85, 4], abs=0.6)
    lo, hi = pb.getAABB(world.movable["panel"], physicsClientId=world.client)
    assert lo[2] > 0.5 and hi[2] > 1.5  # carried upright, well off the floor
    assert tree.blackboard.as_dict()["holding"] is True
    assert tree.blackboard.as_dict()["held"] == "panel"
    # the panel moves with the hand: drive the arm and watch the panel follow
    before = np.asarray(
        pb.getBasePositionAndOrientation(world.movable["panel"], physicsClientId=world.client)[0]
    )
    report, _ = run_xml(world, '<MoveJoints targets="90;-39;48;-56;85;4" speed="0.3"/>')
    assert report.status == "SUCCESS", report.reason
    after = np.asarray(
        pb.getBasePositionAndOrientation(world.movable["panel"], physicsClientId=world.client)[0]
    )
    assert np.linalg.norm(after - before) > 0.2


def test_attach_refuses_an_object_out_of_reach(house_at_pregrasp: World) -> None:
    world = house_at_pregrasp
    report, _ = run_xml(
        world, '<Sequence><MoveJoints state="tuck"/><Attach object="panel"/></Sequence>'
    )
    assert report.status == "FAILURE"
    why = reasons(report)["Attach"]
    assert "'panel' is" in why and "from the fingers (must touch or be within 1.0 cm)" in why
    assert not world.attachments.is_attached("panel")
    panel = world.movable["panel"]
    z = pb.getBasePositionAndOrientation(panel, physicsClientId=world.client)[0][2]
    assert z == pytest.approx(0.075, abs=0.002)


def test_target_outside_joint_limits_fails_before_moving(house_at_pregrasp: World) -> None:
    world = house_at_pregrasp
    q0 = world.robots["husky"].arm_positions()
    report, _ = run_xml(world, '<MoveJointsSequentially targets="0;0;200;0;0;0" order="2"/>')
    assert report.status == "FAILURE"
    assert (
        "joint 2 (elbow_joint) target 200.0 deg is outside its limits"
        in reasons(report)["MoveJointsSequentially"]
    )
    assert np.allclose(world.robots["husky"].arm_positions(), q0, atol=1e-3)


def test_arm_stops_and_fails_when_it_hits_a_wall() -> None:
    from bhelpers import ROOT

    with World(ROOT / "worlds" / "tb3_house.yaml", seed=0) as world:
        # facing the west wall of the workshop, 25 cm from it, arm unfolding towards it
        place_robot(world, "husky", -2.25, -2.0, np.pi)
        # without a planner the arm moves and stops on the contact
        report, _ = run_xml(
            world, '<MoveJoints targets="90;-20;10;-90;0;0" speed="0.3" planner="none"/>')
        assert report.status == "FAILURE"
        why = reasons(report)["MoveJoints"]
        assert "touched 'wall_x_m3'" in why
        # it stopped there instead of pushing on
        q = world.robots["husky"].arm_positions()
        world.step(240)
        assert np.allclose(world.robots["husky"].arm_positions(), q, atol=0.02)


def test_the_planner_refuses_a_goal_inside_a_wall_before_the_arm_moves() -> None:
    from bhelpers import ROOT

    with World(ROOT / "worlds" / "tb3_house.yaml", seed=0) as world:
        place_robot(world, "husky", -2.25, -2.0, np.pi)
        q0 = world.robots["husky"].arm_positions()
        report, _ = run_xml(world, '<MoveJoints targets="90;-20;10;-90;0;0" speed="0.3"/>')
        assert report.status == "FAILURE"
        why = reasons(report)["MoveJoints"]
        assert "the goal is in collision" in why and "wall_x_m3" in why
        assert np.allclose(world.robots["husky"].arm_positions(), q0, atol=0.02)


def test_a_joint_whose_sweep_meets_the_wall_is_refused_before_it_moves() -> None:
    from bhelpers import ROOT

    with World(ROOT / "worlds" / "tb3_house.yaml", seed=0) as world:
        place_robot(world, "husky", -2.25, -2.0, np.pi)
        robot = world.robots["husky"]
        q0 = robot.arm_positions()
        # from the tuck the shoulder rises freely; unfolding the elbow then would swing the
        # forearm into the wall
        report, _ = run_xml(world, '<MoveJointsSequentially targets="90;-20;10;-90;0;0" '
                                   'order="1;2;3;4;5;0"/>')
        assert report.status == "FAILURE"
        why = reasons(report)["MoveJointsSequentially"]
        assert why.startswith("joint 2 (elbow_joint) would collide on its way: ")
        assert "wall_x_m3" in why
        world.step(240)
        q = robot.arm_positions()
        assert abs(q[2] - q0[2]) < 0.02  # the elbow never moved
        assert abs(q[1] - np.radians(-20)) < 0.02  # the shoulder did


def test_close_on_nothing_reports_not_holding(table: World) -> None:
    report, tree = run_xml(
        table, '<Sequence><OpenGripper/><CloseGripper holding="{h}" object="{o}"/></Sequence>'
    )
    assert report.status == "SUCCESS"
    assert tree.blackboard.as_dict()["h"] is False
    assert table.robots["sawyer"].gripper_opening() == pytest.approx(0.0, abs=2e-3)
    report, _ = run_xml(table, '<CloseGripper require_object="true"/>')
    assert report.status == "FAILURE"
    assert "closed on nothing" in reasons(report)["CloseGripper"]


def test_unknown_object_and_robot_give_reasons(table: World) -> None:
    report, _ = run_xml(table, '<Attach object="teapot"/>')
    assert "no movable object named 'teapot'" in reasons(report)["Attach"]
    report, _ = run_xml(table, '<OpenGripper robot="r2d2"/>')
    assert "no robot named 'r2d2'; robots: sawyer" in reasons(report)["OpenGripper"]


def test_spawn_and_delete_models(table: World) -> None:
    report, _ = run_xml(
        table,
        "<Sequence>"
        '<SpawnModel model="block_0"/><SpawnModel model="block_1"/>'
        '<SpawnModel model="crate" size="0.1;0.1;0.1" pose="1.2;0.3;0.8;0.5"'
        ' mass="0.5" colour="blue"/>'
        '<Sleep msec="1000"/><DeleteModel model="block_0"/></Sequence>',
    )
    assert report.status == "SUCCESS", report.reason
    assert sorted(table.movable) == ["block_1", "crate"]
    crate = table.movable["crate"]
    pos, _ = pb.getBasePositionAndOrientation(crate, physicsClientId=table.client)
    assert pos[2] == pytest.approx(0.7475 + 0.05, abs=0.003)  # fell onto the table top
    block = pb.getBasePositionAndOrientation(
        table.movable["block_1"], physicsClientId=table.client
    )[0]
    assert block[2] == pytest.approx(0.7725, abs=0.002)  # a model of the world file, resting
    report, _ = run_xml(
        table, '<SpawnModel model="ghost" size="0.05;0.05;0.05" pose="0.7;0.1;0.7725;0"/>'
    )
    why = reasons(report)["SpawnModel"]
    assert "'ghost' would start" in why and "inside 'block_1'" in why
    assert "ghost" not in table.movable
    report, _ = run_xml(table, '<SpawnModel model="block_1"/>')
    assert "a body named 'block_1' already exists" in reasons(report)["SpawnModel"]
    report, _ = run_xml(table, '<DeleteModel model="block_0"/>')
    assert "no object or furniture named 'block_0'" in reasons(report)["DeleteModel"]
    report, _ = run_xml(table, '<SpawnModel model="blocks_1"/>')
    assert reasons(report)["SpawnModel"] == (
        "no model named 'blocks_1' in sawyer_table.yaml (did you mean 'block_1', 'block_9', "
        "'block_8'?); its models: block_0, block_1, block_2, block_3, block_4, block_5, block_6, "
        "block_7, block_8, block_9; for a new primitive give shape, size and pose"
    )


def test_spawned_sphere_and_cylinder_fall_onto_the_table(table: World) -> None:
    report, _ = run_xml(
        table,
        "<Sequence>"
        '<SpawnModel model="ball" shape="sphere" size="0.03" pose="1.2;0.3;0.9;0" mass="0.2"/>'
        '<SpawnModel model="can" shape="cylinder" size="0.04;0.12" pose="1.2;-0.3;0.95;0"/>'
        '<Sleep msec="1500"/></Sequence>',
    )
    assert report.status == "SUCCESS", report.reason
    top = 0.7475  # the table top
    for name, x, y, half_height in (("ball", 1.2, 0.3, 0.03), ("can", 1.2, -0.3, 0.06)):
        pos, _ = pb.getBasePositionAndOrientation(
            table.movable[name], physicsClientId=table.client
        )
        assert pos == pytest.approx((x, y, top + half_height), abs=0.003), name
        speed = np.linalg.norm(
            pb.getBaseVelocity(table.movable[name], physicsClientId=table.client)[0]
        )
        assert speed < 0.01, name  # resting, not rolling away


def test_spawn_model_values_a_port_cannot_take_are_errors_of_the_tree(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from bt_manip.cli import main

    tree = tmp_path / "spawn.xml"
    tree.write_text(
        '<root BTCPP_format="4"><BehaviorTree ID="Main"><Sequence>\n'
        '<SpawnModel model="a" shape="sphere" size="0.03;0.1" pose="1;0;1;0" mass="-1"/>\n'
        '<SpawnModel model="b" shape="cone" colour="pink" friction="nan" pose="1;2"/>\n'
        '<SpawnModel model="c" size="0.1;0;0.1" pose="1;0;1;inf"/>\n'
        "</Sequence></BehaviorTree></root>\n"
    )
    assert main(["validate", str(tree)]) == 2
    err = capsys.readouterr().err
    bad = f"{tree}:{{}}: bad value for port '{{}}' of SpawnModel: {{}}"
    assert err.splitlines() == [
        bad.format(2, "mass", "must be >= 0, got -1"),
        bad.format(2, "size", "a sphere takes 1 size value (radius), got 2: [0.03, 0.1]"),
        bad.format(3, "shape", "must be one of box, cylinder, sphere, got cone"),
        bad.format(3, "colour", "must be one of beige, black, blue, brown, cyan, dark_grey, "
                                "green, grey, orange, purple, red, white, wood, yellow, got pink"),
        bad.format(3, "friction", "expected a finite number, got 'nan'"),
        bad.format(3, "pose", "must hold 0 or 4 values, got 2"),
        bad.format(4, "size", "each value must be > 0, got 0.1;0;0.1"),
        bad.format(4, "pose", "expected a finite number, got 'inf'"),
    ]
    world = ROOT / "worlds" / "sawyer_table.yaml"
    assert main(["run", str(tree), "--world", str(world), "--quiet"]) == 2
    assert capsys.readouterr().err.splitlines()[0] == bad.format(2, "mass", "must be >= 0, got -1")


def test_spawn_model_value_from_the_blackboard_out_of_range_fails_with_the_reason(
    table: World,
) -> None:
    report, _ = run_xml(
        table,
        '<Sequence><Script code="m := -2.0"/>'
        '<SpawnModel model="d" size="0.05;0.05;0.05" pose="1.2;0;0.8;0" mass="{m}"/></Sequence>',
    )
    assert report.status == "FAILURE"
    assert reasons(report)["SpawnModel"] == (
        "SpawnModel (line 1): input port 'mass' (entry 'm'): must be >= 0, got -2.0"
    )
    assert "d" not in table.movable


def test_injected_slip_drops_the_carried_panel(house_at_pregrasp: World) -> None:
    from bt_manip.bt import load_tree_string
    from bt_manip.run.faults import FaultInjector, FaultSpec
    from bt_manip.run.runner import Runner, RunOptions

    world = house_at_pregrasp
    faults = FaultInjector([FaultSpec("slip", 1.0)], seed=0, clock=world.clock)
    xml = f'<root BTCPP_format="4"><BehaviorTree ID="Main">{PICK}</BehaviorTree></root>'
    tree = load_tree_string(
        xml, context=RunContext.for_world(world, faults=faults)
    )
    report = Runner(tree, world, RunOptions(max_sim_time=60)).run()
    assert report.status == "FAILURE"
    assert [e.kind for e in faults.events][:1] == ["slip"]
    assert not world.attachments.is_attached("panel")
    world.step(480)
    lo, _ = pb.getAABB(world.movable["panel"], physicsClientId=world.client)
    assert lo[2] < 0.05  # it fell to the floor


def test_move_to_pose_reaches_the_pose_and_retreats_first(table: World) -> None:
    from bt_manip.bt import load_tree_string
    from bt_manip.run.runner import Runner, RunOptions

    robot = table.robots["sawyer"]
    report, first = run_xml(table, '<MoveToPose position="0.75;0.2;0.9" approach="0.1"/>')
    assert report.status == "SUCCESS", report.reason
    tip = robot.link_transform("grasp_frame")
    assert np.allclose(tip[:3, 3], [0.75, 0.2, 0.9], atol=0.01)
    assert isinstance(first.context, RunContext)
    target = first.context.overlay.items["ik_target"]  # what a viewer draws as a triad
    assert np.allclose(target.matrix[:3, 3], [0.75, 0.2, 0.9])
    assert tip[2, 2] == pytest.approx(-1.0, abs=0.01)  # tool pointing down
    tips = sample_every_step(table, lambda: robot.link_transform("grasp_frame")[:3, 3].copy())
    xml = (
        '<root BTCPP_format="4"><BehaviorTree ID="Main">'
        '<MoveToPose position="0.75;-0.1;0.9" retreat="0.1"/></BehaviorTree></root>'
    )
    tree = load_tree_string(xml, context=RunContext.for_world(table))
    report = Runner(tree, table, RunOptions(max_sim_time=30)).run()
    assert report.status == "SUCCESS", report.reason
    # it backed up along the tool axis (straight up) before moving across: the retreat's
    # waypoints are passed through loosely, so the peak is short of 1.0 by a few cm
    path = np.array(tips)
    peak = int(path[:, 2].argmax())
    assert path[peak, 2] > 0.95
    assert np.allclose(path[: peak + 1, :2], [0.75, 0.2], atol=0.01)
    assert np.allclose(robot.link_transform("grasp_frame")[:3, 3], [0.75, -0.1, 0.9], atol=0.01)
    report, _ = run_xml(table, '<MoveToPose position="2.5;0;0.9"/>')
    assert report.status == "FAILURE"
    assert "beyond reach" in reasons(report)["MoveToPose"]
