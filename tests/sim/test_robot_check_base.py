"""``robot check`` drives a wheeled or holonomic base straight and turns it on the spot, and
names what holds a slow base back: a differential-drive robot written here whose casters drag
on the floor (high friction, on ``fixed`` joints) fails, with frictionless casters it passes,
and the shipped husky_ur3 and omni_sawyer pass the whole check."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from bt_manip.cli import main
from bt_manip.sim.robot_check import CheckReport, check_robot
from bt_manip.sim.robot_description import RobotDescription

WHEEL_RADIUS = 0.08
CASTERS = ("caster_front", "caster_back")
INERTIA = '<inertia ixx="{i}" ixy="0" ixz="0" iyy="{i}" iyz="0" izz="{i}"/>'
DRAG = "{lateral_friction: 1.0, rolling_friction: 0.0, spinning_friction: 0.0}"
FREE = "{lateral_friction: 0.0, rolling_friction: 0.0, spinning_friction: 0.0}"


def _link(
    name: str, mass: float, collision: str = "", contact: str = "", com: str = "0 0 0"
) -> str:
    return (
        f'  <link name="{name}">{collision}{contact}<inertial><origin xyz="{com}"/>'
        f'<mass value="{mass}"/>{INERTIA.format(i=max(mass * 0.01, 1e-4))}</inertial></link>'
    )


def _urdf(tmp_path: Path, contact: str = "") -> Path:
    """A 10 kg box chassis (frame at the wheel axles, 8 cm up, its centre of mass 10 cm ahead of
    them) on two 8 cm wheels on continuous joints, left and right, and two 4 cm sphere casters on
    fixed joints, front and back, reaching the floor: the front one carries about half the
    weight. A one-joint arm on top. ``contact`` (a ``<contact>`` element) is given
    to the chassis and both casters alike."""
    wheel = f'<collision><origin rpy="1.5708 0 0"/><geometry><cylinder radius="{WHEEL_RADIUS}" ' \
        'length="0.04"/></geometry></collision>'
    ball = '<collision><geometry><sphere radius="0.04"/></geometry></collision>'
    lines = [
        '<robot name="diffy">',
        _link("chassis", 10.0, '<collision><origin xyz="0 0 0.05"/><geometry>'
              '<box size="0.4 0.3 0.1"/></geometry></collision>', contact, com="0.1 0 0.05"),
    ]
    for side, y in (("left", 0.18), ("right", -0.18)):
        lines += [
            f'  <joint name="{side}_wheel" type="continuous"><parent link="chassis"/>'
            f'<child link="{side}_wheel_link"/><origin xyz="0 {y} 0"/><axis xyz="0 1 0"/>'
            "</joint>",
            _link(f"{side}_wheel_link", 1.0, wheel),
        ]
    for name, x in zip(CASTERS, (0.15, -0.15), strict=True):
        lines += [
            f'  <joint name="{name}_joint" type="fixed"><parent link="chassis"/>'
            f'<child link="{name}"/><origin xyz="{x} 0 -0.04"/></joint>',
            _link(name, 0.5, ball, contact),
        ]
    lines += [
        '  <joint name="mount_joint" type="fixed"><parent link="chassis"/><child link="mount"/>'
        '<origin xyz="0 0 0.1"/></joint>',
        _link("mount", 0.2),
        '  <joint name="j1" type="revolute"><parent link="mount"/><child link="tip"/>'
        '<origin xyz="0 0 0.05"/><axis xyz="0 0 1"/>'
        '<limit lower="-1.5" upper="1.5" velocity="1" effort="10"/></joint>',
        _link("tip", 0.2, '<collision><origin xyz="0 0 0.05"/><geometry>'
              '<cylinder radius="0.02" length="0.1"/></geometry></collision>'),
        "</robot>",
    ]
    path = tmp_path / "diffy.urdf"
    path.write_text("\n".join(lines) + "\n")
    return path


def _descriptor(tmp_path: Path, caster_contact: str | None, urdf_contact: str = "") -> Path:
    """``diffy.yaml`` for :func:`_urdf`; ``caster_contact`` (a flow mapping) replaces both
    casters' contact through the recipe's ``contacts:`` section."""
    _urdf(tmp_path, urdf_contact)
    if caster_contact is None:
        source = "urdf: diffy.urdf"
    else:
        rows = "".join(f"    {name}: {caster_contact}\n" for name in CASTERS)
        source = f"urdf:\n  base: diffy.urdf\n  contacts:\n{rows}"
    text = f"""name: diffy
{source.rstrip()}
spawn_height: {WHEEL_RADIUS + 0.001}
base:
  type: skid_steer
  left_wheels: [left_wheel]
  right_wheels: [right_wheel]
  wheel_radius: {WHEEL_RADIUS}
  track_width: 0.36
  max_wheel_speed: 12.0
  wheel_max_torque: 20.0
arm:
  base_link: mount
  joints: [j1]
  velocity_limits: [1.0]
end_effector: tip
grasp_frame: tip
states:
  home: [0.0]
  tuck: [0.0]
footprint:
  length: 0.5
  width: 0.44
"""
    path = tmp_path / "diffy.yaml"
    path.write_text(text)
    return path


def _base_rows(report: CheckReport) -> dict[str, bool]:
    return {m.phase: m.ok for m in report.moves if m.joint == "base"}


def test_dragging_casters_fail_the_drive_and_are_named(
    tmp_path: Path, capsys: pytest.CaptureFixture
) -> None:
    path = _descriptor(tmp_path, DRAG)
    report = check_robot(RobotDescription.load(path))
    rows = _base_rows(report)
    assert set(rows) == {"drive", "turn"}
    assert not rows["drive"] and not report.ok, report.table()
    drive = next(c for c in report.causes if c.startswith("base drive:"))
    assert "caster_front" in drive and "caster_back" in drive, drive
    assert "touch the floor" in drive and "fixed links" in drive and "contacts:" in drive
    # the arm moves still pass: only the base is slow
    assert all(m.ok for m in report.moves if m.joint != "base")
    assert main(["robot", "check", str(path)]) == 1
    out = capsys.readouterr().out
    assert "moves missed" in out and "base drive:" in out and "caster_front" in out


def test_casters_folded_into_the_chassis_are_still_named(tmp_path: Path) -> None:
    """Casters whose contact is the chassis's are folded into it when loaded headless; the
    cause names them all the same, not the chassis."""
    sticky = "<contact><lateral_friction value=\"1.0\"/></contact>"
    report = check_robot(RobotDescription.load(_descriptor(tmp_path, None, sticky)))
    assert not _base_rows(report)["drive"], report.table()
    drive = next(c for c in report.causes if c.startswith("base drive:"))
    assert "caster_front" in drive and "caster_back" in drive and "chassis" not in drive, drive


def test_frictionless_casters_pass_the_drive_and_the_turn(tmp_path: Path) -> None:
    report = check_robot(RobotDescription.load(_descriptor(tmp_path, FREE)))
    assert report.ok, report.table() + "\n" + "\n".join(report.causes)
    assert _base_rows(report) == {"drive": True, "turn": True}
    assert report.causes == []


def test_weak_wheel_motors_are_named_when_nothing_drags(tmp_path: Path) -> None:
    path = _descriptor(tmp_path, FREE)
    path.write_text(path.read_text().replace("wheel_max_torque: 20.0", "wheel_max_torque: 0.05"))
    report = check_robot(RobotDescription.load(path))
    assert _base_rows(report) == {"drive": False, "turn": False}, report.table()
    drive = next(c for c in report.causes if c.startswith("base drive:"))
    assert "nothing but the driven wheels drags" in drive and "wheel_max_torque" in drive, drive


@pytest.mark.parametrize("name", ["husky_ur3", "omni_sawyer"])
def test_shipped_mobile_robots_pass_the_whole_check(name: str) -> None:
    report = check_robot(RobotDescription.load(name))
    assert report.ok, report.table() + "\n" + "\n".join(report.causes)
    assert list(_base_rows(report)) == ["drive", "turn"]
    if name == "omni_sawyer":  # the square is still driven before
        phases = [m.phase for m in report.moves if m.joint.startswith("base_")]
        assert phases == ["+", "+", "back", "back", "turn", "back"]


def test_a_joint_whose_limits_say_unlimited_is_turned_a_turn_each_way(tmp_path: Path) -> None:
    # URDFs written by simulators give a free joint +-1e16 (example-robot-data's iris): the
    # check turns it one turn each way, as a joint without limits, in bounded time
    urdf = tmp_path / "spinner.urdf"
    urdf.write_text(
        '<robot name="spinner">\n' + _link("base", 5.0, '<collision><geometry><box size="0.2 '
                                           '0.2 0.1"/></geometry></collision>') + "\n"
        '  <joint name="spin" type="revolute"><parent link="base"/><child link="blade"/>'
        '<origin xyz="0 0 0.1"/><axis xyz="0 0 1"/>'
        '<limit lower="-1e+16" upper="1e+16" effort="5" velocity="2"/></joint>\n'
        + _link("blade", 0.2, '<collision><geometry><box size="0.3 0.02 0.01"/></geometry>'
                "</collision>") + "\n</robot>\n")
    out = tmp_path / "spinner.yaml"
    assert main(["robot", "init", str(urdf), "--base-link", "base", "--arm-tip", "blade",
                 "--out", str(out)]) == 0
    report = check_robot(RobotDescription.load(out))
    targets = [(m.phase, round(m.target, 4)) for m in report.moves]
    turn = round(2 * math.pi - max(0.02, 0.02 * 4 * math.pi), 4)
    assert targets == [("lower", -turn), ("upper", turn), ("back", 0.0)]
    assert all(m.ok for m in report.moves)


def test_an_arm_whose_limits_leave_zero_out_spawns_at_its_nearest_limit(tmp_path: Path) -> None:
    # PyBullet loads joints at 0; a Kinova's 2nd, 3rd and 5th joints cannot be there
    import pybullet as pb

    from bt_manip.sim.robot import Robot

    urdf = tmp_path / "bent.urdf"
    box = '<collision><geometry><box size="0.1 0.1 0.1"/></geometry></collision>'
    urdf.write_text(
        '<robot name="bent">\n' + _link("base", 5.0, box) + "\n"
        + "".join(
            f'  <joint name="j{i}" type="revolute"><parent link="{parent}"/>'
            f'<child link="l{i}"/><origin xyz="0 0 0.2"/><axis xyz="0 1 0"/>'
            f'<limit lower="{lo}" upper="{hi}" effort="50" velocity="1"/></joint>\n'
            + _link(f"l{i}", 0.5, box) + "\n"
            for i, (parent, lo, hi) in enumerate(
                [("base", 0.5, 1.5), ("l0", -1.0, 1.0), ("l1", -2.0, -0.25)]))
        + "</robot>\n")
    out = tmp_path / "bent.yaml"
    assert main(["robot", "init", str(urdf), "--base-link", "base", "--arm-tip", "l2",
                 "--out", str(out)]) == 0
    client = pb.connect(pb.DIRECT)
    try:
        robot = Robot.spawn(client, RobotDescription.load(out), 0.0, 0.0, 0.0)
        assert list(robot.arm_positions()) == pytest.approx([0.5, 0.0, -0.25], abs=1e-9)
    finally:
        pb.disconnect(client)
