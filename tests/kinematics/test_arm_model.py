"""ArmModel: chain extraction, forward kinematics, Jacobian, reach, errors."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from kin_helpers import COMPOSITE_CHAIN, reference_pose

from bt_manip.kinematics import ArmModel, KinematicsError
from bt_manip.sim.assets import ur3_urdf


def test_ur3_chain(ur3: ArmModel) -> None:
    assert ur3.nq == 6
    assert ur3.joint_names == [
        "shoulder_pan_joint",
        "shoulder_lift_joint",
        "elbow_joint",
        "wrist_1_joint",
        "wrist_2_joint",
        "wrist_3_joint",
    ]
    np.testing.assert_allclose(ur3.lower, [-2 * np.pi] * 2 + [-np.pi] + [-2 * np.pi] * 3)
    np.testing.assert_allclose(ur3.upper, -ur3.lower)
    assert all(j.kind == "revolute" for j in ur3.chain)


def test_ur3_fk_matches_whole_robot(ur3: ArmModel) -> None:
    rng = np.random.default_rng(0)
    for _ in range(50):
        q = ur3.random_configuration(rng)
        named = dict(zip(ur3.joint_names, q, strict=True))
        expected = reference_pose(ur3_urdf(), "base_link", "tool0", named)
        np.testing.assert_allclose(ur3.fk(q), expected, atol=1e-12)


def test_ur3_home_pose_matches_dh_figures(ur3: ArmModel) -> None:
    # All joints at zero: the arm is stretched out horizontally; the tool flange sits at
    # x = -(a2 + a3), y = -(d4 + d6), z = d1 - d5 in base_link (UR convention, mirrored base).
    pose = ur3.fk(np.zeros(6))
    a2, a3, d1, d4, d5, d6 = 0.24365, 0.21325, 0.1519, 0.11235, 0.08535, 0.0819
    assert abs(abs(pose[0, 3]) - (a2 + a3)) < 1e-3
    assert abs(abs(pose[1, 3]) - (d4 + d6)) < 2e-3
    assert abs(pose[2, 3] - (d1 - d5)) < 1e-3


def test_composite_robot_keeps_only_the_arm_chain(
    composite: ArmModel, composite_urdf: Path
) -> None:
    assert composite.joint_names == COMPOSITE_CHAIN
    kinds = [j.kind for j in composite.chain]
    assert kinds == ["revolute"] * 3 + ["prismatic"] + ["revolute"] * 3
    np.testing.assert_allclose(composite.chain[2].axis, [0.0, 0.6, 0.8])
    # The continuous joint gets one full turn of range.
    assert composite.lower[5] == pytest.approx(-np.pi)
    assert composite.upper[5] == pytest.approx(np.pi)
    rng = np.random.default_rng(1)
    for _ in range(30):
        q = composite.random_configuration(rng)
        named = dict(zip(composite.joint_names, q, strict=True))
        # Wheels, lift and fingers move too: base -> tip must not depend on them.
        named.update(wheel_left=rng.uniform(-3, 3), wheel_right=rng.uniform(-3, 3),
                     lift=rng.uniform(0, 0.4), finger_left=0.03, finger_right=0.01)
        expected = reference_pose(composite_urdf, "arm_base", "tool", named)
        np.testing.assert_allclose(composite.fk(q), expected, atol=1e-12)


@pytest.mark.parametrize("which", ["ur3", "composite", "sawyer"])
def test_jacobian_matches_finite_differences(which: str, request: pytest.FixtureRequest) -> None:
    arm: ArmModel = request.getfixturevalue(which)
    rng = np.random.default_rng(2)
    h = 1e-6
    for _ in range(10):
        q = arm.random_configuration(rng)
        jac = arm.jacobian(q)
        pose = arm.fk(q)
        for i in range(arm.nq):
            dq = np.zeros(arm.nq)
            dq[i] = h
            moved = arm.fk(q + dq)
            lin = (moved[:3, 3] - pose[:3, 3]) / h
            skew = (moved[:3, :3] - pose[:3, :3]) / h @ pose[:3, :3].T
            ang = np.array([skew[2, 1], skew[0, 2], skew[1, 0]])
            np.testing.assert_allclose(jac[:3, i], lin, atol=1e-5)
            np.testing.assert_allclose(jac[3:, i], ang, atol=1e-5)


def test_sawyer_chain(sawyer: ArmModel) -> None:
    assert sawyer.joint_names == [f"right_j{i}" for i in range(7)]
    assert sawyer.lower[1] == pytest.approx(-3.8095)
    assert sawyer.upper[1] == pytest.approx(2.2736)
    assert sawyer.upper[6] == pytest.approx(4.7124)


@pytest.mark.parametrize("which", ["ur3", "composite", "sawyer"])
def test_reach_covers_sampled_configurations(which: str, request: pytest.FixtureRequest) -> None:
    arm: ArmModel = request.getfixturevalue(which)
    rng = np.random.default_rng(3)
    shoulder = arm.shoulder()
    farthest = max(
        float(np.linalg.norm(arm.fk(arm.random_configuration(rng))[:3, 3] - shoulder))
        for _ in range(3000)
    )
    assert farthest <= arm.reach() + 1e-9
    assert arm.reach() <= arm.reach_bound() + 1e-12
    # The maximised reach is tight: sampling gets within a few centimetres of it.
    assert arm.reach() - farthest < 0.05


def test_ur3_reach_figure(ur3: ArmModel) -> None:
    # Shoulder to flange with the arm stretched: about 0.59 m for the UR3 (0.5 m nominal
    # reach is measured from the base axis to the wrist).
    assert 0.55 < ur3.reach() < 0.62


def test_missing_link_names_the_links(tmp_path: Path) -> None:
    with pytest.raises(KinematicsError) as info:
        ArmModel.from_urdf(ur3_urdf(), "base_link", "gripper_tip")
    text = str(info.value)
    assert "tip_link 'gripper_tip' is not a link of the robot" in text
    assert "tool0" in text


def test_tip_above_base_is_refused() -> None:
    with pytest.raises(KinematicsError, match="is not below base_link"):
        ArmModel.from_urdf(ur3_urdf(), "tool0", "base_link")


def test_no_joint_between_links_is_refused() -> None:
    with pytest.raises(KinematicsError, match="no movable joint"):
        ArmModel.from_urdf(ur3_urdf(), "wrist_3_link", "tool0")


def test_missing_file_and_bad_xml(tmp_path: Path) -> None:
    with pytest.raises(KinematicsError, match="URDF file not found"):
        ArmModel.from_urdf(tmp_path / "nope.urdf")
    bad = tmp_path / "bad.urdf"
    bad.write_text("<robot name='x'><link name='a'></robot")
    with pytest.raises(KinematicsError, match="cannot read URDF"):
        ArmModel.from_urdf(bad, "a", "b")


def test_wrong_q_length_is_refused(ur3: ArmModel) -> None:
    with pytest.raises(ValueError, match="expected 6 joint values"):
        ur3.fk(np.zeros(5))
