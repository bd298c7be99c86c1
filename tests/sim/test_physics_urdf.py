"""The file PyBullet loads headless: no visuals, STL collision meshes as their hulls, and the
same body (links, masses, collision shapes) as the composed file gives."""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pybullet as pb
import pytest

from bt_manip.sim.compose import composed_urdf
from bt_manip.sim.physics_urdf import hull_triangles, physics_urdf, read_stl_vertices, stl_bytes
from bt_manip.sim.robot_description import RobotDescription


def _body(path: Path) -> list[tuple]:
    """Per link: name, mass, collision geometry types and the set of each mesh's vertices as
    PyBullet built them."""
    c = pb.connect(pb.DIRECT)
    try:
        b = pb.loadURDF(str(path), flags=pb.URDF_USE_INERTIA_FROM_FILE, physicsClientId=c)
        out = []
        for link in range(-1, pb.getNumJoints(b, physicsClientId=c)):
            name = pb.getJointInfo(b, link, physicsClientId=c)[12] if link >= 0 else b"root"
            mass = pb.getDynamicsInfo(b, link, physicsClientId=c)[0]
            shapes = []
            for i, s in enumerate(pb.getCollisionShapeData(b, link, physicsClientId=c)):
                verts: frozenset = frozenset()
                if s[2] == pb.GEOM_MESH:
                    _, v = pb.getMeshData(b, link, collisionShapeIndex=i, physicsClientId=c)
                    verts = frozenset(map(tuple, v))
                shapes.append((s[2], tuple(s[3]), tuple(s[5]), tuple(s[6]), verts))
            out.append((name, mass, shapes))
        return out
    finally:
        pb.disconnect(c)


@pytest.mark.parametrize("robot", ["husky_ur3", "panda"])
def test_physics_file_builds_the_same_body_without_visuals(robot: str) -> None:
    full = composed_urdf(RobotDescription.load(robot))
    physics = physics_urdf(full)
    assert physics != full
    root = ET.parse(physics).getroot()
    assert root.find(".//visual") is None
    meshes = [m.get("filename", "") for m in root.iter("mesh")]
    assert meshes and all(m.endswith(".stl") and "/hulls/" in m for m in meshes)
    assert _body(physics) == _body(full)
    assert physics_urdf(full) == physics  # cached


def test_a_urdf_without_meshes_is_loaded_as_it_is() -> None:
    sawyer = composed_urdf(RobotDescription.load("sawyer"))
    assert physics_urdf(sawyer) == sawyer


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
