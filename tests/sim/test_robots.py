"""The two robots (husky_ur3, sawyer): loading, rest, driving, joint control, FK, gripper.

Every test runs on its own PyBullet DIRECT client: a plane, 240 Hz, gravity -9.81, manual
stepping, cone friction off (as the World sets it).
"""

from __future__ import annotations

import math
import re
import textwrap
from collections.abc import Iterator
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np
import pinocchio as pin
import pybullet as pb
import pybullet_data
import pytest
import yaml

from bt_manip.errors import InputError
from bt_manip.sim.assets import REPO_ROOT
from bt_manip.sim.compose import composed_urdf
from bt_manip.sim.robot import Robot, RobotDescription

RATE = 240
ROBOTS = ("husky_ur3", "sawyer")
PREGRASP_DEG = [70, 11, 78, -56, 85, 4]          # Scenario A, joints 0..5
LIFT_DELTA_DEG = [0, -50, -30, 0, 0, 0]


@pytest.fixture
def client() -> Iterator[int]:
    cid = pb.connect(pb.DIRECT)
    pb.setGravity(0, 0, -9.81, physicsClientId=cid)
    pb.setTimeStep(1.0 / RATE, physicsClientId=cid)
    pb.setPhysicsEngineParameter(enableConeFriction=0, physicsClientId=cid)
    pb.loadURDF(str(Path(pybullet_data.getDataPath()) / "plane.urdf"), physicsClientId=cid)
    yield cid
    pb.disconnect(cid)


@pytest.fixture(scope="module")
def descriptions() -> dict[str, RobotDescription]:
    return {name: RobotDescription.load(name) for name in ROBOTS}


def step(cid: int, seconds: float) -> None:
    for _ in range(round(seconds * RATE)):
        pb.stepSimulation(physicsClientId=cid)


def root_position(robot: Robot) -> np.ndarray:
    return robot.link_pose(robot.link_name(-1))[0]


# -- loading ------------------------------------------------------------------------------------
@pytest.mark.parametrize("name", ROBOTS)
def test_loads_as_one_multibody(client: int, descriptions: dict, name: str) -> None:
    robot = Robot.spawn(client, descriptions[name], 0.5, -0.5, 0.2)
    assert pb.getNumBodies(physicsClientId=client) == 2          # plane + robot
    d = descriptions[name]
    assert len(robot.arm_joint_ids) == len(d.arm.joints)
    for link in (d.end_effector, d.grasp_frame, d.arm.base_link, *d.gripper.finger_links):
        assert robot.has_link(link)
    x, y, yaw = robot.base_pose2d()
    assert (x, y, yaw) == pytest.approx((0.5, -0.5, 0.2), abs=1e-6)


def test_committed_robot_files_have_no_absolute_paths() -> None:
    def strings(value: object) -> Iterator[str]:
        if isinstance(value, str):
            yield value
        elif isinstance(value, dict):
            for v in value.values():
                yield from strings(v)
        elif isinstance(value, list):
            for v in value:
                yield from strings(v)

    checked = 0
    for path in sorted((REPO_ROOT / "robots").rglob("*")):
        if path.suffix == ".urdf":
            values = re.findall(r'filename="([^"]*)"', path.read_text())
        elif path.suffix == ".yaml":
            values = list(strings(yaml.safe_load(path.read_text())))
        else:
            continue
        checked += 1
        for value in values:
            assert not Path(value).is_absolute() and not re.match(r"[A-Za-z]:[\\/]", value), (
                f"{path} holds an absolute path: {value}")
    assert checked >= 5


def test_composed_urdf_resolves_meshes_and_is_stable(descriptions: dict, tmp_path: Path,
                                                     monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("BT_MANIP_CACHE", str(tmp_path / "cache"))
    husky = descriptions["husky_ur3"]
    with ThreadPoolExecutor(4) as pool:          # several loaders at once: one file, atomically
        paths = set(pool.map(lambda _: composed_urdf(husky), range(8)))
    assert len(paths) == 1
    path = paths.pop()
    assert path.parent == tmp_path / "cache"
    assert [p.name for p in path.parent.iterdir()] == [path.name]   # no temporary left over
    text = path.read_text()
    assert "package://" not in text and "pybullet_data://" not in text and "$(" not in text
    meshes = [line.split('filename="')[1].split('"')[0] for line in text.splitlines()
              if 'filename="' in line]
    assert len(meshes) > 10 and all(Path(m).is_absolute() and Path(m).is_file() for m in meshes)
    model = pin.buildModelFromUrdf(str(path))
    assert [model.names[i] for i in range(1, model.njoints)][:4] == [
        "front_left_wheel", "front_right_wheel", "rear_left_wheel", "rear_right_wheel"]
    # a link name is never also a joint name (Pinocchio frame look-ups stay unambiguous)
    for d in descriptions.values():
        m = pin.buildModelFromUrdf(str(composed_urdf(d)))
        for link in (d.end_effector, d.grasp_frame, d.arm.base_link):
            assert len([f for f in m.frames if f.name == link]) == 1


# -- rest ---------------------------------------------------------------------------------------
@pytest.mark.parametrize("name", ROBOTS)
def test_rest_without_commands(client: int, descriptions: dict, name: str) -> None:
    robot = Robot.spawn(client, descriptions[name], 1.0, 2.0, 0.3)
    robot.reset_arm("home")
    base0, q0, g0 = root_position(robot), robot.arm_positions(), robot.gripper_opening()
    step(client, 10.0)
    assert np.linalg.norm(root_position(robot) - base0) < 1e-3
    assert np.abs(robot.arm_positions() - q0).max() < 1e-3
    assert abs(robot.gripper_opening() - g0) < 1e-4
    assert np.abs(robot.arm_velocities()).max() < 1e-3
    assert np.abs(robot.base_velocity()).max() < 1e-3


# -- base ---------------------------------------------------------------------------------------
def test_husky_drives_straight_the_expected_distance(client: int, descriptions: dict) -> None:
    robot = Robot.spawn(client, descriptions["husky_ur3"], 0.0, 0.0, 0.7)
    robot.reset_arm("tuck")
    x0, y0, yaw0 = robot.base_pose2d()
    omega, seconds = 5.0, 5.0
    robot.set_wheel_velocities(omega, omega)
    step(client, seconds)
    x1, y1, yaw1 = robot.base_pose2d()
    expected = omega * descriptions["husky_ur3"].base.wheel_radius * seconds
    assert math.hypot(x1 - x0, y1 - y0) == pytest.approx(expected, rel=0.05)
    heading = math.atan2(y1 - y0, x1 - x0)
    assert abs(heading - yaw0) < 0.05 and abs(yaw1 - yaw0) < 0.05
    assert robot.base_velocity()[0] == pytest.approx(omega * 0.17775, rel=0.05)
    robot.stop_base()
    step(client, 1.0)
    assert np.abs(robot.base_velocity()).max() < 1e-2


def test_husky_turns_at_the_commanded_rate(client: int, descriptions: dict) -> None:
    robot = Robot.spawn(client, descriptions["husky_ur3"], 0.0, 0.0, 0.0)
    robot.reset_arm("tuck")
    robot.set_base_twist(0.0, 0.5)
    step(client, 0.5)
    turned, prev = 0.0, robot.base_pose2d()[2]
    for _ in range(3 * RATE):
        pb.stepSimulation(physicsClientId=client)
        yaw = robot.base_pose2d()[2]
        turned += (yaw - prev + math.pi) % (2 * math.pi) - math.pi
        prev = yaw
    assert turned == pytest.approx(0.5 * 3.0, rel=0.15)


def test_twist_beyond_wheel_limit_is_scaled(client: int, descriptions: dict) -> None:
    robot = Robot.spawn(client, descriptions["husky_ur3"], 0.0, 0.0, 0.0)
    robot.set_base_twist(5.0, 0.0)                       # 28 rad/s asked, 6 rad/s allowed
    step(client, 2.0)
    limit = descriptions["husky_ur3"].base.max_wheel_speed
    wheel_speeds = [pb.getJointState(robot.body, j, physicsClientId=client)[1]
                    for j in robot.wheel_ids_left + robot.wheel_ids_right]
    assert max(wheel_speeds) == pytest.approx(limit, rel=0.02)


# -- arm ----------------------------------------------------------------------------------------
@pytest.mark.parametrize("name", ROBOTS)
def test_every_arm_joint_reaches_its_target(client: int, descriptions: dict, name: str) -> None:
    d = descriptions[name]
    robot = Robot.spawn(client, d, 0.0, 0.0, 0.0)
    robot.reset_arm("home")
    home = np.array(d.state("home"))
    signs = np.array([1.0 if i % 2 == 0 else -1.0 for i in range(len(home))])
    for offset in (0.4, -0.3):
        target = home + offset * signs
        robot.set_arm_targets(target)
        step(client, 3.0)
        assert np.abs(robot.arm_positions() - target).max() < 0.01
    for i in range(len(home)):                      # one joint at a time, as Scenario A does
        target = robot.arm_positions()
        target[i] += 0.5
        robot.set_arm_targets(target)
        step(client, 1.5)
        assert abs(robot.arm_positions()[i] - target[i]) < 0.01


def test_scenario_a_configurations_are_reached(client: int, descriptions: dict) -> None:
    robot = Robot.spawn(client, descriptions["husky_ur3"], 0.0, 0.0, 0.0)
    robot.reset_arm("tuck")
    for q_deg in (PREGRASP_DEG, np.add(PREGRASP_DEG, LIFT_DELTA_DEG)):
        target = np.radians(q_deg)
        robot.set_arm_targets(target)
        step(client, 4.0)
        assert np.abs(robot.arm_positions() - target).max() < 0.01
    assert np.linalg.norm(root_position(robot)[:2]) < 0.01      # the arm did not drag the base


def test_max_velocity_limits_joint_speed(client: int, descriptions: dict) -> None:
    robot = Robot.spawn(client, descriptions["sawyer"], 0.0, 0.0, 0.0)
    robot.reset_arm("home")
    target = np.array(descriptions["sawyer"].state("home"))
    target[0] += 1.0
    robot.set_arm_targets(target, max_velocity=0.5)
    step(client, 0.5)
    assert abs(robot.arm_velocities()[0]) <= 0.5 + 1e-3
    assert robot.arm_positions()[0] - target[0] + 1.0 == pytest.approx(0.25, abs=0.03)


# -- kinematics: Pinocchio and PyBullet agree -----------------------------------------------------
@pytest.mark.parametrize("name", ROBOTS)
def test_pinocchio_fk_matches_pybullet(client: int, descriptions: dict, name: str) -> None:
    d = descriptions[name]
    robot = Robot.spawn(client, d, 0.0, 0.0, 0.0)
    model = pin.buildModelFromUrdf(str(composed_urdf(d)))
    data = model.createData()
    q_index = [model.joints[model.getJointId(j)].idx_q for j in d.arm.joints]
    root = robot.link_name(-1)
    rng = np.random.default_rng(7)
    lower = np.maximum(d.arm.lower, -math.pi)
    upper = np.minimum(d.arm.upper, math.pi)
    for _ in range(100):
        q = rng.uniform(lower, upper)
        for j, v in zip(robot.arm_joint_ids, q, strict=True):
            pb.resetJointState(robot.body, j, v, physicsClientId=client)
        q_pin = pin.neutral(model)
        q_pin[q_index] = q
        pin.framesForwardKinematics(model, data, q_pin)
        base_inv = np.linalg.inv(robot.link_transform(root))
        for link in (d.end_effector, d.grasp_frame):
            bullet = base_inv @ robot.link_transform(link)
            frame = data.oMf[model.getFrameId(link, pin.BODY)]
            assert np.abs(bullet[:3, 3] - frame.translation).max() < 1e-6
            assert np.abs(bullet[:3, :3] - frame.rotation).max() < 1e-6


# -- gripper ------------------------------------------------------------------------------------
@pytest.mark.parametrize("name", ROBOTS)
def test_gripper_closes_and_opens_on_nothing(client: int, descriptions: dict, name: str) -> None:
    robot = Robot.spawn(client, descriptions[name], 0.0, 0.0, 0.0)
    robot.reset_arm("home")
    robot.open_gripper()
    step(client, 1.5)
    assert robot.gripper_opening() == pytest.approx(0.1, abs=1e-3)
    robot.close_gripper()
    step(client, 1.5)
    assert robot.gripper_opening() == pytest.approx(0.0, abs=1e-3)
    robot.set_gripper(0.04)
    step(client, 1.0)
    assert robot.gripper_opening() == pytest.approx(0.04, abs=1e-3)


# Sawyer posture with the grasp frame pointing straight down at (0.75, 0.1, 0.7725), and one
# with the hand about 15 cm higher (found once with a damped least-squares IK on sawyer.urdf).
SAWYER_GRASP = [-0.0964, -0.2049, 0.0333, 1.0382, -0.0485, 0.7381, 1.6915]
SAWYER_LIFTED = [-0.0882, -0.4934, 0.0145, 1.1922, -0.0167, 0.8721, 1.6747]


def test_sawyer_holds_a_cube_by_friction(client: int, descriptions: dict) -> None:
    robot = Robot.spawn(client, descriptions["sawyer"], 0.0, 0.0, 0.0)
    robot.reset_arm(SAWYER_GRASP)
    robot.open_gripper()
    step(client, 1.0)
    grasp = robot.link_transform("grasp_frame")
    assert grasp[:3, 2] @ np.array([0.0, 0.0, -1.0]) > 0.999          # pointing down
    centre = grasp[:3, 3]
    half = 0.025
    table = pb.createMultiBody(
        0.0, pb.createCollisionShape(pb.GEOM_BOX, halfExtents=[0.1, 0.1, 0.02],
                                     physicsClientId=client),
        basePosition=[centre[0], centre[1], centre[2] - half - 0.02], physicsClientId=client)
    cube = pb.createMultiBody(
        0.1, pb.createCollisionShape(pb.GEOM_BOX, halfExtents=[half] * 3, physicsClientId=client),
        basePosition=centre.tolist(),
        baseOrientation=pb.getQuaternionFromEuler([0, 0, math.atan2(grasp[1, 0], grasp[0, 0])]),
        physicsClientId=client)
    pb.changeDynamics(cube, -1, lateralFriction=1.0, physicsClientId=client)
    pb.changeDynamics(table, -1, lateralFriction=1.0, physicsClientId=client)
    step(client, 0.5)
    robot.close_gripper()
    step(client, 1.5)
    assert robot.gripper_opening() == pytest.approx(2 * half, abs=2e-3)
    assert robot.is_grasping(cube)
    cube_z0 = pb.getBasePositionAndOrientation(cube, physicsClientId=client)[0][2]
    hand_z0 = robot.link_pose("grasp_frame")[0][2]
    robot.set_arm_targets(SAWYER_LIFTED)
    step(client, 2.0)
    cube_z1 = pb.getBasePositionAndOrientation(cube, physicsClientId=client)[0][2]
    hand_z1 = robot.link_pose("grasp_frame")[0][2]
    assert hand_z1 - hand_z0 > 0.10
    assert cube_z1 - cube_z0 == pytest.approx(hand_z1 - hand_z0, abs=0.01)
    assert robot.is_grasping(cube)
    step(client, 2.0)                                                   # and it stays there
    assert pb.getBasePositionAndOrientation(cube, physicsClientId=client)[0][2] == pytest.approx(
        cube_z1, abs=0.005)


# -- descriptors --------------------------------------------------------------------------------
def write_descriptor(tmp_path: Path, edit: tuple[str, str] | None = None) -> Path:
    text = (REPO_ROOT / "robots" / "sawyer.yaml").read_text()
    text = text.replace("urdf: sawyer.urdf", f"urdf: {REPO_ROOT / 'robots' / 'sawyer.urdf'}")
    if edit:
        assert edit[0] in text
        text = text.replace(*edit)
    path = tmp_path / "robot.yaml"
    path.write_text(text)
    return path


def test_descriptor_loads_by_name_and_by_path(tmp_path: Path) -> None:
    by_name = RobotDescription.load("sawyer")
    by_path = RobotDescription.load(write_descriptor(tmp_path))
    assert by_name.arm.joints == by_path.arm.joints
    assert by_name.base.type == "fixed" and by_name.gripper.max_opening == pytest.approx(0.1)
    husky = RobotDescription.load("husky_ur3")
    assert husky.base.type == "skid_steer" and husky.base.wheel_radius == pytest.approx(0.17775)
    assert len(husky.arm.lower) == 6 and husky.arm.upper[2] == pytest.approx(math.pi)


@pytest.mark.parametrize(("edit", "message"), [
    (("  type: fixed", "  type: hover"), "base.type must be one of"),
    (("grasp_frame: grasp_frame", "grasp_frame: palm"), "grasp_frame: no link 'palm'"),
    (("right_j6]", "right_j9]"), "arm.joints: no joint 'right_j9'"),
    (("  max_force: 40.0", "  max_force: -1"), "gripper.max_force must be > 0"),
    (("  tuck: [0.0, -1.7,", "  tuck: [0.0,"), "states.tuck must be a list of 7 numbers"),
    (("  tuck: [0.0, -1.7,", "  tuck: [9.0, -1.7,"), "states.tuck: outside the joint limits"),
    (("footprint:", "footprnt:"), "unknown key 'footprnt'"),
    (("urdf: ", "urdf: missing/"), "not found"),
])
def test_bad_descriptor_names_file_line_and_key(tmp_path: Path, edit: tuple[str, str],
                                                message: str) -> None:
    path = write_descriptor(tmp_path, edit)
    with pytest.raises(InputError) as caught:
        RobotDescription.load(path)
    text = str(caught.value)
    assert message in text
    assert str(path) in text
    problem = next(p for p in caught.value.problems if message in p.message)
    assert problem.line is not None
    key = edit[1].split(":")[0].strip()
    assert key in path.read_text().splitlines()[problem.line - 1]


def test_unknown_robot_lists_the_known_ones() -> None:
    with pytest.raises(InputError, match="known robots: husky_ur3, omni_sawyer, panda, sawyer"):
        RobotDescription.load("r2d2")


def test_bad_recipe_is_reported(tmp_path: Path) -> None:
    text = (REPO_ROOT / "robots" / "husky_ur3.yaml").read_text()
    text = text.replace("parts/parallel_gripper.urdf", str(REPO_ROOT / "robots/parts/nope.urdf"))
    text = text.replace("      drop_links: [world]", "      drop_links: [world]\n      colour: red")
    path = tmp_path / "husky.yaml"
    path.write_text(textwrap.dedent(text))
    with pytest.raises(InputError) as caught:
        RobotDescription.load(path)
    messages = [p.message for p in caught.value.problems]
    assert any("unknown key 'colour'" in m for m in messages)
    assert any("nope.urdf' not found" in m for m in messages)
    assert all(p.line is not None for p in caught.value.problems)


def test_husky_gripper_holds_a_plate_edge_at_the_scenario_a_pregrasp(client: int,
                                                                      descriptions: dict) -> None:
    robot = Robot.spawn(client, descriptions["husky_ur3"], 0.0, 0.0, 0.0)
    robot.reset_arm(np.radians(PREGRASP_DEG))
    robot.set_gripper(0.03)
    step(client, 0.5)
    grasp = robot.link_transform("grasp_frame")
    assert grasp[2, 3] > 0.1 and grasp[0, 3] > 0.55          # low, ahead of the bumper
    quat = pb.getQuaternionFromEuler(_euler_xyz(grasp[:3, :3]))
    rotation = np.reshape(pb.getMatrixFromQuaternion(quat), (3, 3))
    assert np.abs(rotation - grasp[:3, :3]).max() < 1e-6
    # a 0.2 x 0.02 x 0.1 m plate (0.3 kg), its thin side between the pads, 2.5 cm deep in them
    centre = grasp[:3, 3] + grasp[:3, 2] * (0.05 - 0.025)
    plate = pb.createMultiBody(
        0.3, pb.createCollisionShape(pb.GEOM_BOX, halfExtents=[0.1, 0.01, 0.05],
                                     physicsClientId=client),
        basePosition=centre.tolist(), baseOrientation=quat, physicsClientId=client)
    robot.close_gripper()
    step(client, 1.0)
    assert robot.gripper_opening() == pytest.approx(0.02, abs=3e-3)
    assert robot.is_grasping(plate)
    lifted = np.radians(np.add(PREGRASP_DEG, LIFT_DELTA_DEG))
    for joint in (1, 2):                                      # one joint at a time
        target = robot.arm_positions()
        target[joint] = lifted[joint]
        robot.set_arm_targets(target)
        step(client, 2.0)
    hand = robot.link_transform("grasp_frame")
    expected = hand[:3, :3] @ (grasp[:3, :3].T @ (centre - grasp[:3, 3])) + hand[:3, 3]
    got = np.array(pb.getBasePositionAndOrientation(plate, physicsClientId=client)[0])
    assert hand[2, 3] - grasp[2, 3] > 0.5
    assert np.linalg.norm(got - expected) < 0.02
    assert robot.is_grasping(plate)


def _euler_xyz(rotation: np.ndarray) -> tuple[float, float, float]:
    """Roll, pitch, yaw (PyBullet's convention) of a rotation matrix."""
    pitch = math.asin(-max(-1.0, min(1.0, rotation[2, 0])))
    roll = math.atan2(rotation[2, 1], rotation[2, 2])
    yaw = math.atan2(rotation[1, 0], rotation[0, 0])
    return roll, pitch, yaw


def test_a_recipe_offset_must_be_finite(tmp_path: Path) -> None:
    text = (REPO_ROOT / "robots" / "husky_ur3.yaml").read_text()
    text = text.replace("xyz: [0.38, 0.0, 0.2243]", "xyz: [.inf, 0.0, 0.2243]")
    text = text.replace("parts/", str(REPO_ROOT / "robots/parts") + "/")
    path = tmp_path / "husky.yaml"
    path.write_text(text)
    with pytest.raises(InputError) as caught:
        RobotDescription.load(path)
    wanted = "xyz must be a list of 3 numbers"
    problem = next(p for p in caught.value.problems if wanted in p.message)
    assert problem.line == 10
