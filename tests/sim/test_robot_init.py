"""``bt-manip robot init`` and ``robot check``: descriptors written from a URDF, their errors
with file and line, the check's table, and a UR3 descriptor used by a world without edits."""

from __future__ import annotations

import math
from pathlib import Path

import pytest
import yaml

from bt_manip.cli import main
from bt_manip.episode import Episode, EpisodeSpec
from bt_manip.errors import InputError
from bt_manip.manipulation.self_collisions import add_planning_section
from bt_manip.sim.assets import example_robot_data_share
from bt_manip.sim.robot_check import check_robot
from bt_manip.sim.robot_description import RobotDescription
from bt_manip.sim.robot_init import InitOptions, init_descriptor

ROOT = Path(__file__).resolve().parents[2]
ERD = example_robot_data_share() / "example-robot-data" / "robots"
PANDA = ERD / "panda_description" / "urdf" / "panda.urdf"
UR3 = ERD / "ur_description" / "urdf" / "ur3_robot.urdf"
PANDA_ARGS = [
    "--base-link", "panda_link0", "--arm-tip", "panda_hand",
    "--gripper", "panda_finger_joint1,panda_finger_joint2", "--grasp-frame", "panda_hand_tcp",
]


def _panda(tmp_path: Path, **kw: object) -> InitOptions:
    base = dict(
        urdf=PANDA, base_link="panda_link0", arm_tip="panda_hand", out=tmp_path / "panda.yaml",
        gripper=("panda_finger_joint1", "panda_finger_joint2"), grasp_frame="panda_hand_tcp",
    )
    base.update(kw)
    return InitOptions(**base)  # type: ignore[arg-type]


def test_panda_descriptor_fields(tmp_path: Path) -> None:
    desc = init_descriptor(_panda(tmp_path))
    assert desc.base.type == "fixed"
    assert desc.arm.joints == tuple(f"panda_joint{i}" for i in range(1, 8))
    assert desc.arm.base_link == "panda_link0" and desc.end_effector == "panda_hand"
    assert desc.grasp_frame == "panda_hand_tcp"
    assert desc.arm.velocity_limits == (2.175,) * 4 + (2.61,) * 3
    assert desc.gripper.finger_links == ("panda_leftfinger", "panda_rightfinger")
    assert (desc.gripper.open, desc.gripper.closed) == (0.04, 0.0)
    assert desc.gripper.max_opening == pytest.approx(0.08)
    assert set(desc.states) == {"home", "tuck", "zero", "ready"}
    # zero is clipped into joint 4's range (-3.0718 .. -0.0698); ready is mid-range
    assert desc.states["zero"][3] == pytest.approx(-0.0698)
    assert desc.states["ready"][3] == pytest.approx((-3.0718 - 0.0698) / 2, abs=1e-4)
    for q in desc.states.values():
        limits = zip(q, desc.arm.lower, desc.arm.upper, strict=True)
        assert all(lo <= v <= hi for v, lo, hi in limits)
    assert 0.1 < desc.footprint.radius < 0.3
    text = (tmp_path / "panda.yaml").read_text()
    assert "package://example-robot-data/robots/panda_description/urdf/panda.urdf" in text
    assert str(ERD) not in text  # no absolute path


def test_committed_panda_descriptor_is_what_init_writes(tmp_path: Path) -> None:
    add_planning_section(init_descriptor(_panda(tmp_path)))  # as robot init writes it
    written = yaml.safe_load((tmp_path / "panda.yaml").read_text())
    committed = yaml.safe_load((ROOT / "robots" / "panda.yaml").read_text())
    assert written == committed


def _problems(opts: InitOptions) -> list[str]:
    with pytest.raises(InputError) as err:
        init_descriptor(opts)
    assert not opts.out.exists()
    return [str(p) for p in err.value.problems]


def test_unknown_links_are_reported(tmp_path: Path) -> None:
    problems = _problems(_panda(tmp_path, base_link="nope", arm_tip="panda_handle"))
    assert any(f"{PANDA}:1: --base-link: no link 'nope'" in p for p in problems)
    assert any("--arm-tip: no link 'panda_handle'" in p for p in problems)


def test_tip_not_below_base(tmp_path: Path) -> None:
    (problem,) = _problems(_panda(tmp_path, base_link="panda_link3", arm_tip="panda_link2"))
    assert problem.startswith(f"{PANDA}:50: --arm-tip: link 'panda_link2' is not below")


def test_gripper_joint_must_be_prismatic_or_revolute(tmp_path: Path) -> None:
    (problem,) = _problems(_panda(tmp_path, gripper=("panda_hand_joint",)))
    assert problem.startswith(f"{PANDA}:218: --gripper: joint 'panda_hand_joint' is fixed")


def test_urdf_that_does_not_parse(tmp_path: Path) -> None:
    bad = tmp_path / "bad.urdf"
    bad.write_text('<robot name="r">\n  <link name="a">\n</robot>\n')
    (problem,) = _problems(_panda(tmp_path, urdf=bad))
    assert problem.startswith(f"{bad}:3: the URDF does not parse")


def test_missing_mesh_is_reported_with_its_line(tmp_path: Path) -> None:
    urdf = tmp_path / "arm.urdf"
    urdf.write_text(
        '<robot name="arm">\n'
        '  <link name="base"/>\n'
        '  <link name="tip">\n'
        '    <visual><geometry><mesh filename="meshes/tip.stl"/></geometry></visual>\n'
        "  </link>\n"
        '  <joint name="j1" type="revolute"><parent link="base"/><child link="tip"/>\n'
        '    <axis xyz="0 0 1"/><limit lower="-1" upper="1" velocity="1" effort="10"/>\n'
        "  </joint>\n"
        "</robot>\n"
    )
    (problem,) = _problems(InitOptions(urdf, "base", "tip", tmp_path / "arm.yaml"))
    assert problem.startswith(f"{urdf}:4: ") and "tip.stl" in problem


def test_cli_init_writes_and_errors_exit_2(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    out = tmp_path / "robots" / "p.yaml"
    assert main(["robot", "init", str(PANDA), *PANDA_ARGS, "--out", str(out)]) == 0
    assert "wrote" in capsys.readouterr().out
    assert RobotDescription.load(out).name == "p"
    bad = tmp_path / "robots" / "q.yaml"
    argv = ["robot", "init", str(PANDA), "--base-link", "x", "--arm-tip", "panda_hand"]
    assert main([*argv, "--out", str(bad)]) == 2
    assert f"{PANDA}:1: --base-link: no link 'x'" in capsys.readouterr().err
    assert not bad.exists()


def test_holonomic_without_virtual_joints_is_refused(tmp_path: Path) -> None:
    (problem,) = _problems(_panda(tmp_path, mobile="holonomic"))
    assert "0 movable joint(s) above --base-link 'panda_link0'" in problem


def test_check_moves_every_joint_to_its_limits(tmp_path: Path) -> None:
    report = check_robot(init_descriptor(_panda(tmp_path)))
    assert report.ok, report.table()
    joints = {m.joint for m in report.moves}
    assert joints == {f"panda_joint{i}" for i in range(1, 8)} | {"gripper"}
    lower = next(m for m in report.moves if m.joint == "panda_joint4" and m.phase == "lower")
    assert lower.reached == pytest.approx(-3.0718, abs=0.1)
    assert [m.phase for m in report.moves if m.joint == "gripper"] == ["open", "close", "open"]


def test_check_fails_when_a_joint_cannot_reach(
    tmp_path: Path, capsys: pytest.CaptureFixture
) -> None:
    desc = init_descriptor(_panda(tmp_path))
    text = (tmp_path / "panda.yaml").read_text()
    # too weak a shoulder to lift the arm against gravity
    weak = text.replace("efforts: [87.0, 87.0,", "efforts: [87.0, 0.5,")
    (tmp_path / "weak.yaml").write_text(weak.replace("name: panda", "name: weak"))
    assert desc.name == "panda"
    assert main(["robot", "check", str(tmp_path / "weak.yaml")]) == 1
    out = capsys.readouterr().out
    assert "panda_joint2" in out and "NO" in out and "moves missed" in out


def test_ur3_descriptor_works_in_a_world_without_edits(tmp_path: Path) -> None:
    (tmp_path / "robots").mkdir()
    desc = init_descriptor(
        InitOptions(UR3, "base_link", "tool0", tmp_path / "robots" / "ur3.yaml")
    )
    assert desc.arm.joints[0] == "shoulder_pan_joint" and desc.gripper.joints == ()
    (tmp_path / "world.yaml").write_text(
        "name: ur3_alone\nrobots:\n  - {name: ur3, description: ur3, pose: [0, 0, 0], "
        "arm_state: home}\n"
    )
    (tmp_path / "tree.xml").write_text(
        '<root BTCPP_format="4"><BehaviorTree ID="Main"><Sequence>\n'
        '  <MoveJoints targets="0;-1.2;1.5;-1.87;-1.5708;0"/>\n'
        '  <MoveToPose position="0.3;0.1;0.25" path="line"/>\n'
        '  <MoveToPose position="0.25;-0.15;0.3"/>\n'
        "</Sequence></BehaviorTree></root>\n"
    )
    spec = EpisodeSpec(tree=str(tmp_path / "tree.xml"), world=str(tmp_path / "world.yaml"))
    with Episode(spec) as episode:
        report = episode.run()
        assert report.status == "SUCCESS", report.reason
        pos, _ = episode.world.robots["ur3"].link_pose("tool0")
        assert math.dist(pos, (0.25, -0.15, 0.3)) < 0.01


def test_mobile_base_wheels_track_and_footprint(tmp_path: Path) -> None:
    """The Husky + UR3 URDF read back as a skid-steer: wheels, track, radius, footprint close to
    the hand-written husky_ur3 descriptor (the geometric track width, 0.5708 m)."""
    urdf = RobotDescription.load("husky_ur3").urdf_path
    desc = init_descriptor(
        InitOptions(
            urdf, "ur3_base_link", "ur3_tool0", tmp_path / "husky.yaml",
            gripper=("gripper_left_finger_joint", "gripper_right_finger_joint"),
            mobile="skid", grasp_frame="grasp_frame",
        )
    )
    assert desc.base.type == "skid_steer"
    assert set(desc.base.left_wheels) == {"front_left_wheel", "rear_left_wheel"}
    assert set(desc.base.right_wheels) == {"front_right_wheel", "rear_right_wheel"}
    assert desc.base.track_width == pytest.approx(0.5708, abs=0.01)
    assert desc.base.wheel_radius == pytest.approx(0.17775, abs=1e-4)  # the URDF cylinder
    assert desc.footprint.length == pytest.approx(0.99, abs=0.05)
    assert desc.footprint.width == pytest.approx(0.67, abs=0.05)
    assert 0.0 <= desc.spawn_height < 0.02
    assert desc.arm.joints[0] == "shoulder_pan_joint" and desc.gripper.max_opening == 0.1


def test_mobile_without_wheels_is_refused(tmp_path: Path) -> None:
    (problem,) = _problems(_panda(tmp_path, mobile="diff"))
    assert "found no continuous wheel joints on both sides" in problem


def test_descriptor_next_to_its_own_urdf_names_it_relatively(tmp_path: Path) -> None:
    urdf = tmp_path / "models" / "arm.urdf"
    urdf.parent.mkdir()
    urdf.write_text(
        '<robot name="arm">\n  <link name="base"/>\n  <link name="mid"/>\n  <link name="tip"/>\n'
        '  <joint name="j1" type="revolute"><parent link="base"/><child link="mid"/>\n'
        '    <axis xyz="0 0 1"/><limit lower="-1" upper="2" velocity="1" effort="10"/>\n'
        "  </joint>\n"
        '  <joint name="j2" type="continuous"><parent link="mid"/><child link="tip"/>\n'
        '    <origin xyz="0 0 0.3"/><axis xyz="0 1 0"/>\n'
        "  </joint>\n</robot>\n"
    )
    desc = init_descriptor(InitOptions(urdf, "base", "tip", tmp_path / "robots" / "arm.yaml"))
    assert "base: ../models/arm.urdf" in (tmp_path / "robots" / "arm.yaml").read_text()
    # mid-range where there are limits, 0 for the continuous joint; the default speed for it
    assert desc.states["ready"] == (0.5, 0.0) and desc.states["zero"] == (0.0, 0.0)
    assert desc.arm.velocity_limits == (1.0, 1.0)


def test_check_by_name_takes_the_descriptor_just_written_here(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture
) -> None:
    monkeypatch.chdir(tmp_path)
    assert main(["robot", "init", str(PANDA), "--base-link", "panda_link0",
                 "--arm-tip", "panda_hand", "--gripper", "panda_finger_joint1,panda_finger_joint2",
                 "--grasp-frame", "panda_hand_tcp", "--out", "robots/mine.yaml"]) == 0
    assert main(["robot", "check", "mine"]) == 0
    assert "panda_joint7" in capsys.readouterr().out
    monkeypatch.chdir(tmp_path / "robots")  # no robots/mine.yaml here, nor a shipped 'mine'
    assert main(["robot", "check", "mine"]) == 2
    assert "no robot descriptor 'mine'" in capsys.readouterr().err
