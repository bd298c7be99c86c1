"""The file PyBullet loads headless: no visuals, STL collision meshes as their hulls, fixed links
merged, and the same rigid assembly (mass, inertia, link frames, collision shapes) as the
composed file gives."""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pybullet as pb
import pytest

from bt_manip.sim.compose import composed_urdf
from bt_manip.sim.fixed_links import merge_fixed_links
from bt_manip.sim.physics_urdf import (
    PhysicsModel,
    hull_triangles,
    physics_model,
    read_stl_vertices,
    stl_bytes,
)
from bt_manip.sim.robot import Robot
from bt_manip.sim.robot_description import RobotDescription


def _assembly(path: Path, description: RobotDescription, merged: dict) -> dict:
    """The loaded body at a fixed pose and joint configuration: total mass, centre of mass and
    inertia about it (world axes), every URDF link's frame, and every collision shape placed in
    the world (type, size, position, the mesh's vertices in world coordinates)."""
    c = pb.connect(pb.DIRECT)
    try:
        b = pb.loadURDF(
            str(path), basePosition=(1.0, 2.0, 0.3),
            baseOrientation=pb.getQuaternionFromEuler((0.1, 0.2, 0.7)),
            flags=pb.URDF_USE_INERTIA_FROM_FILE, physicsClientId=c,
        )
        robot = Robot(c, b, description, merged)
        for k, j in enumerate(robot.arm_joint_ids):
            pb.resetJointState(b, j, 0.3 * (k + 1) - 1.0, physicsClientId=c)
        for j in robot.gripper_joint_ids:
            pb.resetJointState(b, j, 0.01, physicsClientId=c)
        masses, coms, tensors, shapes = [], [], [], []
        for link in range(-1, pb.getNumJoints(b, physicsClientId=c)):
            dyn = pb.getDynamicsInfo(b, link, physicsClientId=c)
            if link == -1:
                pos, quat = pb.getBasePositionAndOrientation(b, physicsClientId=c)
            else:
                pos, quat = pb.getLinkState(b, link, computeForwardKinematics=1,
                                            physicsClientId=c)[:2]
            rot = np.array(pb.getMatrixFromQuaternion(quat)).reshape(3, 3)
            masses.append(dyn[0])
            coms.append(np.array(pos))
            tensors.append(rot @ np.diag(dyn[2]) @ rot.T)
            for i, shape in enumerate(pb.getCollisionShapeData(b, link, physicsClientId=c)):
                spos, squat = pb.multiplyTransforms(pos, quat, shape[5], shape[6])
                np.array(pb.getMatrixFromQuaternion(squat)).reshape(3, 3)
                verts = np.zeros((0, 3))
                if shape[2] == pb.GEOM_MESH:
                    _, v = pb.getMeshData(b, link, collisionShapeIndex=i, physicsClientId=c)
                    verts = np.array(v) @ rot.T + np.array(pos)  # given in the link frame
                shapes.append((shape[2], tuple(np.round(shape[3], 6)), np.array(spos), verts))
        total = sum(masses)
        com = sum(m * p for m, p in zip(masses, coms, strict=True)) / total
        inertia = sum(
            t + m * (float((p - com) @ (p - com)) * np.eye(3) - np.outer(p - com, p - com))
            for m, p, t in zip(masses, coms, tensors, strict=True)
        )
        frames = {
            name: robot.link_pose(name)
            for name in set(robot._links) | set(robot.merged_frames)
        }
        return {"links": pb.getNumJoints(b, physicsClientId=c), "mass": total, "com": com,
                "inertia": inertia, "frames": frames,
                "shapes": sorted(shapes, key=lambda s: (s[0], s[1], *np.round(s[2], 2)))}
    finally:
        pb.disconnect(c)


@pytest.mark.parametrize("robot", ["husky_ur3", "panda", "sawyer"])
def test_physics_file_builds_the_same_assembly_with_fewer_links(robot: str) -> None:
    description = RobotDescription.load(robot)
    full = composed_urdf(description)
    model = physics_model(full)
    assert model.path != full
    root = ET.parse(model.path).getroot()
    assert root.find(".//visual") is None
    assert not [j for j in root.iter("joint") if j.get("type") == "fixed"]
    meshes = [m.get("filename", "") for m in root.iter("mesh")]
    assert all(m.endswith(".stl") and "/hulls/" in m for m in meshes)
    before = _assembly(full, description, {})
    after = _assembly(model.path, description, model.merged)
    assert after["links"] < before["links"]
    assert after["mass"] == pytest.approx(before["mass"], rel=1e-12)
    assert after["com"] == pytest.approx(before["com"], abs=1e-9)
    assert after["inertia"] == pytest.approx(before["inertia"], abs=1e-6)
    assert set(after["frames"]) == set(before["frames"])
    for name, (pos, quat) in before["frames"].items():
        got_pos, got_quat = after["frames"][name]
        assert got_pos == pytest.approx(pos, abs=1e-6), name
        assert abs(float(np.dot(got_quat, quat))) == pytest.approx(1.0, abs=1e-6), name  # float32
    assert len(after["shapes"]) == len(before["shapes"])
    for (kind, size, pos, verts), (kind0, size0, pos0, verts0) in zip(
        after["shapes"], before["shapes"], strict=True
    ):
        assert (kind, size) == (kind0, size0)
        assert pos == pytest.approx(pos0, abs=1e-5)
        assert len(verts) == len(verts0)
        if len(verts):  # the same points, in any order
            gaps = np.linalg.norm(verts[:, None, :] - verts0[None, :, :], axis=2).min(axis=1)
            assert gaps.max() < 1e-5
    assert physics_model(full) == model  # cached, frames included


def test_a_urdf_without_meshes_or_fixed_joints_is_loaded_as_it_is(tmp_path: Path) -> None:
    plain = tmp_path / "arm.urdf"
    plain.write_text(
        '<robot name="arm"><link name="a"/><link name="b"/>'
        '<joint name="j" type="revolute"><parent link="a"/><child link="b"/>'
        '<axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>'
        "</robot>"
    )
    assert physics_model(plain) == PhysicsModel(plain)


def _two_cubes(contact: str = "") -> ET.Element:
    i = 2.0 / 6.0  # a 2 kg unit cube
    cube = (
        f'<inertial><mass value="2"/><inertia ixx="{i}" ixy="0" ixz="0" iyy="{i}" iyz="0" '
        f'izz="{i}"/></inertial>'
        '<collision><geometry><box size="1 1 1"/></geometry></collision>'
    )
    return ET.fromstring(
        f'<robot name="t"><link name="a">{cube}</link><link name="b">{cube}{contact}</link>'
        '<link name="c"/>'
        '<joint name="weld" type="fixed"><parent link="a"/><child link="b"/>'
        '<origin xyz="1 0 0" rpy="0 0 1.5707963267948966"/></joint>'
        '<joint name="hinge" type="revolute"><parent link="b"/><child link="c"/>'
        '<origin xyz="0 0 0.5"/><axis xyz="0 0 1"/>'
        '<limit lower="-1" upper="1" effort="1" velocity="1"/></joint></robot>'
    )


def _floats(text: str | None) -> list[float]:
    return [float(v) for v in (text or "").split()]


def test_two_welded_cubes_become_one_box_of_twice_the_length() -> None:
    root = _two_cubes()
    merged = merge_fixed_links(root)
    assert set(merged) == {"b"}
    assert merged["b"].carrier == "a"
    assert merged["b"].position == pytest.approx((1.0, 0.0, 0.0))
    assert [el.get("name") for el in root.findall("link")] == ["a", "c"]
    inertial = root.find("link/inertial")
    assert inertial is not None
    assert float(inertial.find("mass").get("value")) == pytest.approx(4.0)  # type: ignore[union-attr]
    assert _floats(inertial.find("origin").get("xyz")) == pytest.approx([0.5, 0.0, 0.0])  # type: ignore[union-attr]
    moments = sorted(float(inertial.find("inertia").get(k)) for k in ("ixx", "iyy", "izz"))  # type: ignore[union-attr]
    # a 2 x 1 x 1 box of 4 kg: (1 + 1) / 3 about its length, (4 + 1) / 3 across it
    assert moments == pytest.approx([4 * 2 / 12, 4 * 5 / 12, 4 * 5 / 12])
    assert len(root.findall("link/collision")) == 2
    hinge = root.find("joint")
    assert hinge is not None and hinge.find("parent").get("link") == "a"  # type: ignore[union-attr]
    assert _floats(hinge.find("origin").get("xyz")) == pytest.approx([1.0, 0.0, 0.5])  # type: ignore[union-attr]


def test_a_link_with_its_own_contact_parameters_is_not_merged() -> None:
    root = _two_cubes('<contact><lateral_friction value="1.5"/></contact>')
    assert merge_fixed_links(root) == {}
    assert len(root.findall("link")) == 3


def test_hull_keeps_only_points_on_the_surface(tmp_path: Path) -> None:
    rng = np.random.default_rng(0)
    inside = rng.uniform(-0.4, 0.4, size=(300, 3))
    corners = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], float)
    points = np.concatenate([inside, corners]).astype(np.float32)
    triangles = hull_triangles(points)
    assert triangles is not None
    kept = {tuple(p) for p in triangles.reshape(-1, 3)}
    assert kept == {tuple(p) for p in corners.astype(np.float32)}
    stl = tmp_path / "hull.stl"
    stl.write_bytes(stl_bytes(triangles))
    assert {tuple(p) for p in read_stl_vertices(stl)} == kept


def test_hull_lists_each_point_once_in_the_order_of_the_mesh() -> None:
    corners = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], np.float32)
    # a mesh's vertex stream repeats each corner (every triangle names its three)
    stream = np.concatenate([corners[[3, 1, 3, 0]], corners, corners[::-1], [[0.0, 0.0, 0.0]]])
    triangles = hull_triangles(stream.astype(np.float32))
    assert triangles is not None
    points = triangles.reshape(-1, 3)
    order = [3, 1, 0, 2, 4, 5, 6, 7]  # first seen: 3, 1, 0, then the rest in turn
    assert points[: len(order)].tolist() == corners[order].tolist()
    assert all((p == points[len(order) - 1]).all() for p in points[len(order):])  # the fill
    assert len(points) == len(order) + (-len(order)) % 3


def test_flat_or_tiny_point_sets_have_no_hull(tmp_path: Path) -> None:
    flat = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0], [0.5, 0.5, 0]], np.float32)
    assert hull_triangles(flat) is None
    assert hull_triangles(flat[:3]) is None
    ascii_stl = tmp_path / "tri.stl"
    ascii_stl.write_text(
        "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\n"
        "endloop\nendfacet\nendsolid t\n"
    )
    assert read_stl_vertices(ascii_stl).shape == (3, 3)
