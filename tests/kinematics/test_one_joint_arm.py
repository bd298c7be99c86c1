"""An arm of one joint (one_joint.urdf: a 0.3 m link turning about z on a fixed base, 0.1 m
up, limits +-2 rad) loads, solves the targets it can reach and says why for the others, and
drives in a world from a descriptor written by ``robot init``."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from bt_manip.episode import Episode, EpisodeSpec
from bt_manip.kinematics import ArmModel
from bt_manip.kinematics.ik import IKOptions, IKSolver
from bt_manip.sim.robot_init import InitOptions, init_descriptor

URDF = Path(__file__).resolve().parent / "one_joint.urdf"
LINK, HEIGHT = 0.3, 0.1


def tip_at(angle: float) -> np.ndarray:
    """Where the tip is (4x4, base frame) with the joint at ``angle``."""
    c, s = math.cos(angle), math.sin(angle)
    pose = np.eye(4)
    pose[:2, :2] = [[c, -s], [s, c]]
    pose[:3, 3] = (LINK * c, LINK * s, HEIGHT)
    return pose


@pytest.fixture(scope="module")
def arm() -> ArmModel:
    return ArmModel.from_urdf(URDF, "base_link", "tool0")


def test_the_chain_fk_jacobian_and_reach_of_one_joint(arm: ArmModel) -> None:
    assert arm.nq == 1 and arm.joint_names == ["pan"]
    assert arm.chain[0].kind == "revolute"
    assert (arm.lower.tolist(), arm.upper.tolist()) == ([-2.0], [2.0])
    for angle in (-1.5, 0.0, 0.7):
        np.testing.assert_allclose(arm.fk(np.array([angle])), tip_at(angle), atol=1e-12)
        jac = arm.jacobian(np.array([angle]))
        assert jac.shape == (6, 1)
        np.testing.assert_allclose(
            jac[:, 0], [-LINK * math.sin(angle), LINK * math.cos(angle), 0, 0, 0, 1], atol=1e-12
        )
    assert arm.reach() == pytest.approx(LINK, abs=1e-6)


@pytest.mark.parametrize("angle", [-1.9, -0.6, 0.0, 0.45, 1.2, 1.95])
def test_ik_solves_every_pose_the_joint_reaches(arm: ArmModel, angle: float) -> None:
    ik = IKSolver(arm, IKOptions(time_budget=None, max_restarts=20))
    result = ik.solve(tip_at(angle))
    assert result.success, result.reason
    assert result.q.tolist() == pytest.approx([angle], abs=1e-4)
    position_only = IKSolver(arm, IKOptions(time_budget=None, max_restarts=20,
                                            position_only=True))
    assert position_only.solve(tip_at(angle)).q.tolist() == pytest.approx([angle], abs=1e-4)


def test_ik_says_why_a_pose_off_the_joints_reach_fails(arm: ArmModel) -> None:
    ik = IKSolver(arm, IKOptions(time_budget=None, max_restarts=20))
    beyond_limit = ik.solve(tip_at(2.5))
    assert not beyond_limit.success
    assert beyond_limit.reason is not None
    assert beyond_limit.reason.startswith("joint limits: the solutions found need pan at 2.50 rad")
    too_far = tip_at(0.5)
    too_far[:3, 3] *= 1.5
    far = ik.solve(too_far)
    assert not far.success and far.reason is not None and far.reason.startswith("beyond reach")
    tilted = tip_at(0.5)
    tilted[:3, :3] = tilted[:3, :3] @ np.array([[1, 0, 0], [0, 0, -1], [0, 1, 0]])  # 90 deg
    assert not ik.solve(tilted).success  # one joint cannot turn the tool about x


def test_robot_init_writes_a_descriptor_that_moves_the_arm_in_a_world(tmp_path: Path) -> None:
    (tmp_path / "robots").mkdir()
    init_descriptor(InitOptions(URDF, "base_link", "tool0", tmp_path / "robots" / "one.yaml"))
    (tmp_path / "world.yaml").write_text(
        "name: one_alone\nrobots:\n  - {name: one, description: one, pose: [1.0, 2.0, 0.0], "
        "arm_state: home}\n"
    )
    # the tool points up whatever the angle: its yaw is left free; x, y in the world
    angle = 0.8
    x, y = 1.0 + LINK * math.cos(angle), 2.0 + LINK * math.sin(angle)
    (tmp_path / "tree.xml").write_text(
        '<root BTCPP_format="4"><BehaviorTree ID="Main"><Sequence>\n'
        f'  <MoveToPose position="{x};{y};{HEIGHT}" orientation="0;0;0;1" free_yaw="true"/>\n'
        "</Sequence></BehaviorTree></root>\n"
    )
    spec = EpisodeSpec(tree=str(tmp_path / "tree.xml"), world=str(tmp_path / "world.yaml"))
    with Episode(spec) as episode:
        report = episode.run()
        assert report.status == "SUCCESS", report.reason
        robot = episode.world.robots["one"]
        pos, _ = robot.link_pose("tool0")
        assert math.dist(pos, (x, y, HEIGHT)) < 0.01
        assert robot.arm_positions().tolist() == pytest.approx([angle], abs=0.02)
