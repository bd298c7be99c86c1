"""Holonomic bases: ``robot init --mobile holonomic`` on a generated URDF (descriptor content,
errors with file and line), and the Robot API driving the virtual x, y, yaw joints (sideways in
the base frame, limits, a wall that stops it, braking)."""

from __future__ import annotations

import math
from pathlib import Path

import pybullet as pb
import pybullet_data
import pytest

from bt_manip.cli import main
from bt_manip.errors import InputError
from bt_manip.manipulation.self_collisions import add_planning_section
from bt_manip.sim.robot import Robot
from bt_manip.sim.robot_check import check_robot
from bt_manip.sim.robot_init import FLOOR_GAP, PUSH_FRICTION, InitOptions, init_descriptor

CHASSIS_MASS = 20.0
LIMIT = '    <limit lower="-50" upper="50" velocity="0.7" effort="0"/>'
"""Of the prismatic joints: a speed, and no effort (0: the force comes from the weight)."""
JOINTS = {
    "x": ("prismatic", "1 0 0", "0 0 0"),
    "y": ("prismatic", "0 1 0", "0 0 0"),
    "yaw": ("continuous", "0 0 1", "0 0 0"),
}


def _urdf(tmp_path: Path, joints: dict[str, tuple[str, str, str]] | None = None) -> Path:
    """A box chassis (0.5 x 0.4 x 0.2 m, centred 5 cm ahead of its frame) hanging from 'odom'
    by the given virtual joints (name -> type, axis, origin rpy; root first), with a two-joint
    arm on a mount."""
    joints = JOINTS if joints is None else joints
    lines = ['<robot name="omni">', '  <link name="odom"/>']
    parent = "odom"
    for name, (jtype, axis, rpy) in joints.items():
        child = f"{name}_link" if name != list(joints)[-1] else "chassis"
        lines += [
            f'  <joint name="{name}" type="{jtype}">',
            f'    <parent link="{parent}"/><child link="{child}"/>',
            f'    <origin xyz="0 0 0" rpy="{rpy}"/><axis xyz="{axis}"/>',
            LIMIT if jtype == "prismatic" else "",
            "  </joint>",
        ]
        if child != "chassis":
            lines.append(
                f'  <link name="{child}"><inertial><mass value="0.1"/>'
                '<inertia ixx="1e-4" ixy="0" ixz="0" iyy="1e-4" iyz="0" izz="1e-4"/>'
                "</inertial></link>"
            )
        parent = child
    lines += [
        '  <link name="chassis">',
        '    <collision><origin xyz="0.05 0 0.1"/><geometry><box size="0.5 0.4 0.2"/>'
        "</geometry></collision>",
        f'    <inertial><origin xyz="0.05 0 0.1"/><mass value="{CHASSIS_MASS}"/>'
        '<inertia ixx="0.3" ixy="0" ixz="0" iyy="0.5" iyz="0" izz="0.7"/></inertial>',
        "  </link>",
        '  <joint name="mount_joint" type="fixed"><parent link="chassis"/>'
        '<child link="mount"/><origin xyz="0 0 0.2"/></joint>',
        '  <link name="mount"><inertial><mass value="0.5"/>'
        '<inertia ixx="1e-3" ixy="0" ixz="0" iyy="1e-3" iyz="0" izz="1e-3"/></inertial></link>',
        '  <joint name="j1" type="revolute"><parent link="mount"/><child link="upper"/>',
        '    <axis xyz="0 0 1"/><limit lower="-2" upper="2" velocity="1" effort="20"/>',
        "  </joint>",
        '  <link name="upper"><collision><origin xyz="0 0 0.1"/><geometry>'
        '<cylinder radius="0.03" length="0.2"/></geometry></collision>'
        '<inertial><origin xyz="0 0 0.1"/><mass value="0.5"/>'
        '<inertia ixx="1e-3" ixy="0" ixz="0" iyy="1e-3" iyz="0" izz="1e-3"/></inertial></link>',
        '  <joint name="j2" type="revolute"><parent link="upper"/><child link="tip"/>',
        '    <origin xyz="0 0 0.2"/><axis xyz="0 1 0"/>'
        '<limit lower="-1.5" upper="1.5" velocity="1" effort="20"/>',
        "  </joint>",
        '  <link name="tip"><inertial><mass value="0.2"/>'
        '<inertia ixx="1e-4" ixy="0" ixz="0" iyy="1e-4" iyz="0" izz="1e-4"/></inertial></link>',
        "</robot>",
    ]
    path = tmp_path / "omni.urdf"
    path.write_text("\n".join(line for line in lines if line) + "\n")
    return path


def _init(tmp_path: Path, urdf: Path | None = None) -> InitOptions:
    return InitOptions(
        urdf or _urdf(tmp_path), "mount", "tip", tmp_path / "robots" / "omni.yaml",
        mobile="holonomic",
    )


def _line_of(path: Path, text: str) -> int:
    return next(i for i, line in enumerate(path.read_text().splitlines(), 1) if text in line)


def test_descriptor_of_a_holonomic_base(tmp_path: Path) -> None:
    desc = init_descriptor(_init(tmp_path))
    base = desc.base
    assert base.type == "holonomic"
    assert base.joints == ("x", "y", "yaw")
    assert base.max_speed == pytest.approx(0.7)  # the URDF velocity of the x / y joints
    assert base.max_yaw_rate == pytest.approx(1.0)  # no velocity given for yaw: the default
    assert base.max_accel > 0 and base.max_yaw_accel > 0
    # no efforts given: the base pushes with half its weight (chassis + arm)
    assert base.max_force == pytest.approx(PUSH_FRICTION * 9.81 * 21.3, rel=0.02)
    assert base.max_torque > 0
    # the chassis box around the base frame (the yaw joint's child), its bottom 3 cm up
    assert desc.footprint.length == pytest.approx(0.5, abs=0.01)
    assert desc.footprint.width == pytest.approx(0.4, abs=0.01)
    assert desc.footprint.x_offset == pytest.approx(0.05, abs=0.01)
    assert desc.spawn_height == pytest.approx(FLOOR_GAP, abs=0.005)
    assert desc.arm.joints == ("j1", "j2")
    text = (tmp_path / "robots" / "omni.yaml").read_text()
    assert "type: holonomic" in text and "joints: [x, y, yaw]" in text


def _problem(opts: InitOptions) -> str:
    with pytest.raises(InputError) as err:
        init_descriptor(opts)
    assert not opts.out.exists()
    (problem,) = err.value.problems
    return str(problem)


def test_missing_virtual_joint_names_the_base_link(tmp_path: Path) -> None:
    urdf = _urdf(tmp_path, {"x": JOINTS["x"], "yaw": JOINTS["yaw"]})
    problem = _problem(_init(tmp_path, urdf))
    line = _line_of(urdf, '<link name="mount"')
    assert problem.startswith(f"{urdf}:{line}: --mobile holonomic: 2 movable joint(s) above")
    assert "'x' (prismatic), 'yaw' (continuous)" in problem


def test_wrong_axis_names_the_joint_line(tmp_path: Path) -> None:
    urdf = _urdf(tmp_path, {**JOINTS, "y": ("prismatic", "1 0 0", "0 0 0")})
    problem = _problem(_init(tmp_path, urdf))
    line = _line_of(urdf, '<joint name="y"')
    assert problem.startswith(f"{urdf}:{line}: --mobile holonomic: joint 'y' must be the y joint")
    assert "axis 1 0 0" in problem


def test_wrong_type_and_rotated_origin_are_refused(tmp_path: Path) -> None:
    urdf = _urdf(tmp_path, {**JOINTS, "yaw": ("prismatic", "0 0 1", "0 0 0")})
    assert "joint 'yaw' must be the yaw joint, continuous or revolute" in _problem(
        _init(tmp_path, urdf)
    )
    urdf = _urdf(tmp_path, {**JOINTS, "x": ("prismatic", "1 0 0", "0 0 0.5")})
    assert "joint 'x' has a rotated origin" in _problem(_init(tmp_path, urdf))


def test_cli_reports_a_fixed_arm_as_having_no_virtual_joints(
    tmp_path: Path, capsys: pytest.CaptureFixture
) -> None:
    urdf = _urdf(tmp_path, {})
    out = tmp_path / "robots" / "arm.yaml"
    argv = ["robot", "init", str(urdf), "--base-link", "mount", "--arm-tip", "tip",
            "--mobile", "holonomic", "--out", str(out)]
    assert main(argv) == 2
    assert "0 movable joint(s) above --base-link 'mount'" in capsys.readouterr().err
    assert not out.exists()


def test_check_drives_the_square_and_the_turn(tmp_path: Path) -> None:
    report = check_robot(init_descriptor(_init(tmp_path)))
    assert report.ok, report.table()
    rows = [(m.joint, m.phase) for m in report.moves if m.joint in ("x", "y", "yaw")]
    assert rows == [("x", "+"), ("y", "+"), ("x", "back"), ("y", "back"),
                    ("yaw", "turn"), ("yaw", "back")]


# -- the Robot API --------------------------------------------------------------------------------
@pytest.fixture
def scene(tmp_path: Path):  # type: ignore[no-untyped-def]
    desc = init_descriptor(_init(tmp_path))
    client = pb.connect(pb.DIRECT)
    pb.setGravity(0, 0, -9.81, physicsClientId=client)
    pb.setTimeStep(1.0 / 240.0, physicsClientId=client)
    pb.loadURDF(str(Path(pybullet_data.getDataPath()) / "plane.urdf"), physicsClientId=client)
    yield client, desc
    pb.disconnect(client)


def _run(client: int, robot: Robot, seconds: float, command: tuple[float, float, float] | None):
    """Step ``seconds`` at 240 Hz, re-sending ``command`` at 20 Hz (None: leave the motors)."""
    for i in range(round(seconds * 240)):
        if command is not None and i % 12 == 0:
            robot.set_base_velocity(*command)
        pb.stepSimulation(physicsClientId=client)


def test_velocity_is_in_the_base_frame(scene) -> None:  # type: ignore[no-untyped-def]
    client, desc = scene
    robot = Robot.spawn(client, desc, 1.0, 2.0, 0.5)
    assert robot.base_pose2d() == pytest.approx((1.0, 2.0, 0.5), abs=1e-4)
    _run(client, robot, 2.0, (0.0, 0.3, 0.0))  # to its left
    x, y, yaw = robot.base_pose2d()
    left = (-math.sin(0.5), math.cos(0.5))
    moved = ((x - 1.0) * left[0] + (y - 2.0) * left[1], (x - 1.0) * left[1] - (y - 2.0) * left[0])
    assert moved[0] == pytest.approx(0.6, abs=0.03) and abs(moved[1]) < 0.01
    assert abs(yaw - 0.5) < 0.01
    vx, vy, w = robot.base_velocity()
    assert abs(vx) < 0.01 and vy == pytest.approx(0.3, abs=0.01) and abs(w) < 0.01


def test_speeds_are_clipped_to_the_limits(scene) -> None:  # type: ignore[no-untyped-def]
    client, desc = scene
    robot = Robot.spawn(client, desc, 0.0, 0.0, 0.0)
    _run(client, robot, 1.0, (3.0, 4.0, 9.0))
    vx, vy, w = robot.base_velocity()
    assert math.hypot(vx, vy) == pytest.approx(desc.base.max_speed, rel=0.05)
    assert vy / vx == pytest.approx(4.0 / 3.0, rel=0.1)  # the direction is kept
    assert w == pytest.approx(desc.base.max_yaw_rate, rel=0.05)


def test_a_wall_stops_the_base(scene) -> None:  # type: ignore[no-untyped-def]
    client, desc = scene
    wall = pb.createCollisionShape(pb.GEOM_BOX, halfExtents=[0.05, 1.0, 0.5],
                                   physicsClientId=client)
    pb.createMultiBody(0, wall, -1, [1.0, 0.0, 0.5], physicsClientId=client)  # face at x=0.95
    robot = Robot.spawn(client, desc, 0.0, 0.0, 0.0)
    _run(client, robot, 5.0, (0.5, 0.0, 0.0))
    front = robot.base_pose2d()[0] + desc.footprint.x_offset + desc.footprint.length / 2.0
    assert 0.9 < front < 0.96  # it drove up to the wall and no further
    vx, _, _ = robot.base_velocity()
    assert abs(vx) < 0.02


def test_stop_base_brakes_where_it_is(scene) -> None:  # type: ignore[no-untyped-def]
    client, desc = scene
    robot = Robot.spawn(client, desc, 0.0, 0.0, 0.0)
    _run(client, robot, 1.5, (0.4, -0.2, 0.6))
    robot.stop_base()
    _run(client, robot, 0.5, None)
    here = robot.base_pose2d()
    _run(client, robot, 2.0, None)
    there = robot.base_pose2d()
    assert math.dist(here[:2], there[:2]) < 0.005 and abs(there[2] - here[2]) < 0.005
    assert max(abs(v) for v in robot.base_velocity()) < 0.01


def test_committed_omni_sawyer_is_what_init_writes_but_its_home_and_tuck(tmp_path: Path) -> None:
    import yaml

    root = Path(__file__).resolve().parents[2] / "robots"
    out = tmp_path / "robots" / "omni_sawyer.yaml"
    add_planning_section(init_descriptor(InitOptions(  # as robot init writes it
        root / "omni_sawyer.urdf", "right_arm_base_link", "right_hand", out,
        gripper=("gripper_left_finger_joint", "gripper_right_finger_joint"),
        grasp_frame="grasp_frame", mobile="holonomic",
    )))
    written = yaml.safe_load(out.read_text())
    committed = yaml.safe_load((root / "omni_sawyer.yaml").read_text())
    sawyer = yaml.safe_load((root / "sawyer.yaml").read_text())
    assert committed["states"]["home"] == sawyer["states"]["home"]
    assert committed["states"]["tuck"] == sawyer["states"]["tuck"]
    assert committed["urdf"] == {"base": "omni_sawyer.urdf"}
    assert written["urdf"]["base"].endswith("robots/omni_sawyer.urdf")  # relative from tmp_path
    for d in (written, committed):
        # the planning section follows the states (tests/manipulation/test_self_collisions.py
        # finds the committed one again from the committed states)
        del d["states"]["home"], d["states"]["tuck"], d["urdf"], d["planning"]
    assert written == committed


def test_descriptor_errors_of_a_holonomic_base(tmp_path: Path) -> None:
    from bt_manip.sim.robot_description import load_description

    init_descriptor(_init(tmp_path))
    good = (tmp_path / "robots" / "omni.yaml").read_text()
    bad = tmp_path / "robots" / "bad.yaml"
    bad.write_text(
        good.replace("joints: [x, y, yaw]", "joints: [x, yaw]")
        .replace("  max_speed: 0.7 ", "  max_speed: 50 ")
        .replace("  type: holonomic", "  type: holonomic\n  track_width: 0.5")
    )
    with pytest.raises(InputError) as err:
        load_description(bad)
    text = "\n".join(str(p) for p in err.value.problems)
    lines = bad.read_text().splitlines()

    def at(key: str) -> str:
        return f"{bad}:{next(i for i, t in enumerate(lines, 1) if t.startswith(f'  {key}:'))}: "

    assert at("joints") + "base.joints of a holonomic base: three joints" in text
    assert at("max_speed") + "base.max_speed must be within" in text
    assert at("track_width") + "unknown key 'track_width' in base" in text
