"""``robot init`` on real robots' URDFs, without edits: TIAGo (a differential-drive base with
casters and a five-finger hand), the Franka Panda (a parallel prismatic gripper) and the SO-101
arm (one revolute jaw). Each descriptor is written, loaded into a world, and every joint moved
and the gripper opened and closed by a tree."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import yaml

from bt_manip.cli import main
from bt_manip.episode import Episode, EpisodeSpec
from bt_manip.errors import InputError
from bt_manip.manipulation.collision_scene import CollisionScene
from bt_manip.manipulation.self_collisions import add_planning_section
from bt_manip.sim.assets import example_robot_data_share
from bt_manip.sim.robot_description import APPROACH_FRAME
from bt_manip.sim.robot_init import InitOptions, init_descriptor

ROOT = Path(__file__).resolve().parents[2]
ERD = example_robot_data_share() / "example-robot-data" / "robots"
TIAGO = ERD / "tiago_description" / "robots" / "tiago.urdf"
PANDA = ERD / "panda_description" / "urdf" / "panda.urdf"
SO101 = ERD / "so_arm_description" / "urdf" / "so101.urdf"
PLANNING_CASES = {
    # a mobile manipulator whose forearm and wrist roll joints are continuous
    "pr2": (ERD / "pr2_description" / "urdf" / "pr2.urdf", "torso_lift_link",
            "r_gripper_tool_frame", ("r_forearm_roll_joint", "r_wrist_roll_joint")),
    # its jaw joint and the link it moves are both called 'gripper'
    "so100": (ERD / "so_arm_description" / "urdf" / "so100.urdf", "base", "gripper", ()),
    # a pelvis mesh whose convex hull qhull refuses to build as it is ("Too many neighbors")
    "centauro": (ERD / "centauro_description" / "urdf" / "centauro.urdf", "pelvis",
                 "arm1_8", ()),
    # meshes named "package:///example-robot-data/..." (an empty host)
    "talos": (ERD / "talos_data" / "robots" / "talos_full_v2.urdf", "torso_2_link",
              "gripper_left_base_link", ()),
}


def _tiago(folder: Path, **kw: object) -> InitOptions:
    base: dict[str, object] = dict(
        urdf=TIAGO, base_link="torso_fixed_link", arm_tip="arm_tool_link",
        out=folder / "tiago.yaml", gripper=("hand_*",), grasp_frame="hand_grasping_frame",
        mobile="diff",
    )
    base.update(kw)
    return InitOptions(**base)  # type: ignore[arg-type]


def test_tiago_hand_casters_footprint_and_approach_axis(tmp_path: Path) -> None:
    notes: list[str] = []
    desc = init_descriptor(_tiago(tmp_path), notes)
    g = desc.gripper
    assert g.kind == "hand"
    # the actuator joints (1 mm spheres) and the spreading joints are left out, and said so
    for left_out in ("hand_thumb_joint", "hand_index_joint", "hand_mrl_joint",
                     "hand_index_abd_joint", "hand_little_abd_joint"):
        assert left_out not in g.joints
        assert any(f"left out '{left_out}'" in n for n in notes)
    assert "hand_index_flex_3_joint" in g.joints and "hand_thumb_abd_joint" in g.joints
    # every flexing joint closes toward its upper limit, measured
    flex = g.joints.index("hand_index_flex_1_joint")
    assert g.closed_positions[flex] == pytest.approx(0.785398, abs=1e-4)
    assert g.open_positions[flex] == 0.0
    assert 0.08 < g.max_opening < 0.3 and g.min_opening == 0.0
    # the hand points along x of its grasp frame: the loader adds the frame placed by the nodes
    assert desc.approach_axis == "x" and desc.grasp_frame == APPROACH_FRAME
    assert desc.grasp_link == "hand_grasping_frame"
    # the base: two driven wheels, four frictionless casters, the shapeless laser link left out
    assert desc.base.left_wheels == ("wheel_left_joint",)
    assert desc.base.right_wheels == ("wheel_right_joint",)
    recipe = desc.urdf
    casters = {f"caster_{w}_2_link" for w in ("front_right", "front_left", "back_right",
                                              "back_left")}
    assert set(recipe.contacts) == casters  # type: ignore[union-attr]
    assert all(v["lateral_friction"] == 0.0 for v in recipe.contacts.values())  # type: ignore[union-attr]
    assert recipe.drop_links == ("hand_safety_box",)  # type: ignore[union-attr]
    assert 0.45 < desc.footprint.length < 0.6 and 0.45 < desc.footprint.width < 0.6
    assert any("rgbd_laser_link" in n or "without a collision shape" in n for n in notes)


@pytest.mark.parametrize("robot", sorted(PLANNING_CASES))
def test_real_robots_that_stopped_robot_init_get_a_descriptor_and_planning(robot: str,
                                                                 tmp_path: Path) -> None:
    urdf, base, tip, turning = PLANNING_CASES[robot]
    desc, allowed = add_planning_section(
        init_descriptor(InitOptions(urdf, base, tip, tmp_path / f"{robot}.yaml")))
    assert allowed.never  # pairs found apart in every sampled configuration
    written = yaml.safe_load((tmp_path / f"{robot}.yaml").read_text())
    never = written["planning"]["allowed_collisions"]["never"]
    assert {frozenset(p) for p in never} == allowed.never
    for joint in turning:
        assert joint in desc.arm.joints
    scene = CollisionScene(desc.urdf_path, list(desc.arm.joints))
    state = np.asarray(desc.state("home"))
    assert scene.within_limits(state)
    assert scene.contacts(state) is not None


def test_shipped_tiago_is_what_init_writes_but_its_states(tmp_path: Path) -> None:
    add_planning_section(init_descriptor(_tiago(tmp_path)))  # as robot init writes it
    written = yaml.safe_load((tmp_path / "tiago.yaml").read_text())
    shipped = yaml.safe_load((ROOT / "robots" / "tiago.yaml").read_text())
    for d in (written, shipped):
        d.pop("states")
    assert written == shipped


def test_hand_actuator_joints_named_explicitly_are_refused(tmp_path: Path) -> None:
    with pytest.raises(InputError) as err:
        init_descriptor(_tiago(tmp_path, gripper=("hand_thumb_joint", "hand_index_joint")))
    (problem,) = err.value.problems
    assert problem.line is not None and problem.file.endswith("tiago.urdf")
    assert "'hand_thumb_joint' cannot move a finger" in problem.message
    assert not (tmp_path / "tiago.yaml").exists()


def test_gripper_pattern_matching_nothing_is_refused(tmp_path: Path) -> None:
    with pytest.raises(InputError, match="no joint matches claw_"):
        init_descriptor(_tiago(tmp_path, gripper=("claw_*",)))


def test_cli_prints_every_assumption(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    code = main([
        "robot", "init", str(SO101), "--base-link", "base_link", "--arm-tip", "gripper_link",
        "--gripper", "gripper", "--grasp-frame", "gripper_frame_link",
        "--out", str(tmp_path / "so101.yaml"),
    ])
    out = capsys.readouterr().out
    assert code == 0
    assert "revolute gripper gripper" in out
    assert "assumed: approach axis z of 'gripper_frame_link'" in out
    assert "assumed: gripper: revolute, 1 joint(s) (rad)" in out


def test_given_approach_axis_wins(tmp_path: Path) -> None:
    desc = init_descriptor(InitOptions(
        SO101, "base_link", "gripper_link", tmp_path / "so101.yaml", gripper=("gripper",),
        grasp_frame="gripper_frame_link", approach_axis="-y",
    ))
    assert desc.approach_axis == "-y" and desc.grasp_frame == APPROACH_FRAME


def _joint_targets(lower: tuple[float, ...], upper: tuple[float, ...], share: float
                   ) -> list[float]:
    """Each joint ``share`` of its range, every other joint ``1 - share`` (a zig-zag that keeps
    an arm standing on the floor clear of it)."""
    out = []
    for i, (lo, hi) in enumerate(zip(lower, upper, strict=True)):
        s = share if i % 2 == 0 else 1.0 - share
        out.append(lo + s * (hi - lo) if np.isfinite(lo) and np.isfinite(hi) else s - 0.5)
    return out


CASES = {
    "tiago": lambda folder: _tiago(folder / "robots"),
    "panda": lambda folder: InitOptions(
        PANDA, "panda_link0", "panda_hand", folder / "robots" / "panda.yaml",
        gripper=("panda_finger_joint1", "panda_finger_joint2"), grasp_frame="panda_hand_tcp",
    ),
    "so101": lambda folder: InitOptions(
        SO101, "base_link", "gripper_link", folder / "robots" / "so101.yaml",
        gripper=("gripper",), grasp_frame="gripper_frame_link",
    ),
}


@pytest.mark.parametrize("robot", sorted(CASES))
def test_written_robot_moves_every_joint_and_its_gripper_in_a_world(
    robot: str, tmp_path: Path
) -> None:
    (tmp_path / "robots").mkdir()
    desc = init_descriptor(CASES[robot](tmp_path))
    first = _joint_targets(desc.arm.lower, desc.arm.upper, 0.4)
    second = _joint_targets(desc.arm.lower, desc.arm.upper, 0.6)
    (tmp_path / "world.yaml").write_text(
        f"name: {robot}_alone\nrobots:\n  - {{name: {robot}, description: {robot}, "
        "pose: [0, 0, 0], arm_state: tuck}\n"
    )
    moves = "\n".join(
        f'  <MoveJoints targets="{";".join(f"{v:.4f}" for v in q)}" units="rad" tolerance="0.02"/>'
        for q in (first, second)
    )
    (tmp_path / "tree.xml").write_text(
        '<root BTCPP_format="4"><BehaviorTree ID="Main"><Sequence>\n'
        '  <OpenGripper name="open"/>\n'
        f"{moves}\n"
        '  <CloseGripper name="close"/>\n'
        "</Sequence></BehaviorTree></root>\n"
    )
    spec = EpisodeSpec(tree=str(tmp_path / "tree.xml"), world=str(tmp_path / "world.yaml"))
    with Episode(spec) as episode:
        report = episode.run()
        assert report.status == "SUCCESS", report.reason
        body = episode.world.robots[robot]
        assert np.allclose(body.arm_positions(), second, atol=0.03)
        assert body.gripper_opening() == pytest.approx(desc.gripper.min_opening, abs=0.005)
        body.open_gripper()
        episode.world.step(round(1.0 / episode.world.dt))
        assert body.gripper_opening() == pytest.approx(desc.gripper.max_opening, abs=0.01)


def _descriptor_problems(tmp_path: Path, edit: dict) -> list[str]:
    from bt_manip.sim.robot_description import load_description

    init_descriptor(CASES["so101"](tmp_path))
    path = tmp_path / "robots" / "so101.yaml"
    data = yaml.safe_load(path.read_text())
    for key, value in edit.items():
        section, _, field = key.partition(".")
        if field:
            data[section][field] = value
        else:
            data[section] = value
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    with pytest.raises(InputError) as err:
        load_description(path)
    return [f"{p.line}: {p.message}" for p in err.value.problems]


@pytest.mark.parametrize(
    ("edit", "expected"),
    [
        ({"gripper.kind": "claw"}, "gripper.kind must be one of parallel, revolute, hand"),
        ({"gripper.width": -1.0}, "gripper.width"),
        ({"gripper.open": [1.0, 2.0]}, "gripper.open must be a list of 1 numbers"),
        ({"gripper.closed": [1.7453]}, "open and closed positions are equal"),
        ({"approach_axis": "w"}, "approach_axis must be one of z, -z, x, -x, y, -y"),
    ],
)
def test_descriptor_gripper_and_approach_errors_name_the_line(
    tmp_path: Path, edit: dict, expected: str
) -> None:
    (tmp_path / "robots").mkdir()
    problems = _descriptor_problems(tmp_path, edit)
    assert any(expected in p and not p.startswith("None") for p in problems), problems


def test_recipe_frames_and_dropped_links(tmp_path: Path) -> None:
    from bt_manip.sim.robot_description import load_description

    (tmp_path / "robots").mkdir()
    init_descriptor(CASES["so101"](tmp_path))
    path = tmp_path / "robots" / "so101.yaml"
    text = path.read_text()
    urdf_line = next(line for line in text.splitlines() if line.startswith("  base:"))
    good = text.replace(urdf_line, urdf_line + "\n  frames:\n    pad_centre: {parent: "
                        "gripper_frame_link, xyz: [0, 0, 0.01]}")
    path.write_text(good.replace("grasp_frame: gripper_frame_link", "grasp_frame: pad_centre"))
    desc = load_description(path)
    assert desc.grasp_frame == "pad_centre"
    bad = text.replace(urdf_line, urdf_line + "\n  drop_links: [gripper_link]")
    path.write_text(bad)
    with pytest.raises(InputError, match="only a leaf link"):
        load_description(path)


def test_package_meshes_resolve_against_the_urdfs_own_package(tmp_path: Path) -> None:
    """``package://my_arm/...`` outside example-robot-data: found in the folder named after the
    package above the URDF, as ROS finds it."""
    import shutil

    from bt_manip.sim.compose import composed_urdf

    package = tmp_path / "ws" / "my_arm"
    (package / "urdf").mkdir(parents=True)
    (package / "meshes").mkdir()
    mesh = ERD / "tiago_description" / "meshes" / "hey5" / "palm_collision.stl"
    shutil.copy(mesh, package / "meshes" / "palm.stl")
    (package / "urdf" / "arm.urdf").write_text(
        '<robot name="arm"><link name="base"><collision><geometry>'
        '<mesh filename="package://my_arm/meshes/palm.stl"/></geometry></collision></link>'
        "</robot>\n"
    )
    text = composed_urdf(package / "urdf" / "arm.urdf").read_text()
    assert str((package / "meshes" / "palm.stl").resolve()) in text


def test_mimic_joint_follows_its_leader(tmp_path: Path) -> None:
    """The Panda's second finger mimics the first: naming the first is enough."""
    notes: list[str] = []
    desc = init_descriptor(InitOptions(
        PANDA, "panda_link0", "panda_hand", tmp_path / "panda.yaml",
        gripper=("panda_finger_joint1",), grasp_frame="panda_hand_tcp",
    ), notes)
    assert desc.gripper.joints == ("panda_finger_joint1", "panda_finger_joint2")
    assert desc.gripper.kind == "parallel" and desc.gripper.max_opening == pytest.approx(0.08)
    assert any("'panda_finger_joint2' mimics 'panda_finger_joint1'" in n for n in notes)


def test_lidar_link_gives_a_laser_in_the_descriptor(tmp_path: Path) -> None:
    notes: list[str] = []
    desc = init_descriptor(_tiago(tmp_path, lidar="base_link"), notes)
    (laser,) = desc.sensors
    assert (laser.name, laser.link, laser.xyz, laser.rpy) == (
        "laser", "base_link", (0.0, 0.0, 0.0), (0.0, 0.0, 0.0))
    assert (laser.fov_deg, laser.beams) == (270.0, 541)
    assert any("the laser at the origin of 'base_link'" in n for n in notes)
    with pytest.raises(InputError, match="--lidar: no link 'nowhere_link'"):
        init_descriptor(_tiago(tmp_path / "bad", lidar="nowhere_link"))
    assert not (tmp_path / "bad" / "tiago.yaml").exists()
