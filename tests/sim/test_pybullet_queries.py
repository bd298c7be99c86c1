"""Named PyBullet query results and the one contact query."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pybullet as pb
import pybullet_data
import pytest

from bt_manip.sim import pybullet_queries as pbq


@pytest.fixture
def client() -> Iterator[int]:
    cid = pb.connect(pb.DIRECT)
    pb.setGravity(0, 0, -9.81, physicsClientId=cid)
    yield cid
    pb.disconnect(cid)


def _box(cid: int, z: float) -> int:
    shape = pb.createCollisionShape(pb.GEOM_BOX, halfExtents=[0.1, 0.1, 0.1], physicsClientId=cid)
    return pb.createMultiBody(1.0, shape, -1, [0.0, 0.0, z], physicsClientId=cid)


def test_a_box_resting_on_the_plane_is_reported_by_name(client: int) -> None:
    plane = pb.loadURDF(str(Path(pybullet_data.getDataPath()) / "plane.urdf"),
                        physicsClientId=client)
    box = _box(client, 0.1)
    pb.stepSimulation(physicsClientId=client)
    found = pbq.contacts(client, box)
    assert found and all(c.body_a == box and c.body_b == plane for c in found)
    assert all(c.normal_force > 0 and c.distance < 1e-3 for c in found)
    assert pbq.contacts(client, box, plane) == found
    assert pbq.touching(client, box) == {plane}
    assert pbq.aabb(client, box).lower[2] == pytest.approx(0.0, abs=2e-3)
    assert pbq.aabb(client, box).upper[2] == pytest.approx(0.2, abs=2e-3)
    near = pbq.closest_points(client, box, plane, 0.05)
    assert near and min(p.distance for p in near) < 1e-3


def test_joints_links_and_shapes_carry_their_names(client: int) -> None:
    body = pb.loadURDF(str(Path(pybullet_data.getDataPath()) / "r2d2.urdf"),
                       physicsClientId=client)
    infos = pbq.joint_infos(client, body)
    assert len(infos) == pbq.joint_count(client, body) > 0
    assert [j.index for j in infos] == list(range(len(infos)))
    assert all(isinstance(j.name, str) and isinstance(j.link_name, str) for j in infos)
    assert pbq.root_link_name(client, body) == "base_link"
    first = infos[0]
    assert first.parent_index == -1
    state = pbq.link_state(client, body, first.index)
    assert len(state.frame_position) == 3 and len(state.frame_orientation) == 4
    assert pbq.link_states(client, body, [first.index])[0] == state
    assert pbq.joint_states(client, body, [first.index])[0].position == pytest.approx(0.0)
    assert pbq.joint_states(client, body, []) == []
    assert pbq.dynamics_info(client, body).mass > 0
    assert any(s.link == -1 for s in pbq.visual_shapes(client, body))
    assert pbq.collision_shapes(client, body, -1)[0].body == body
    pos, quat = pbq.com_pose(client, body, -1)
    assert len(pos) == 3 and len(quat) == 4


def test_a_ray_names_the_body_it_hits(client: int) -> None:
    box = _box(client, 0.5)
    hit, miss = pbq.ray_hits(client, [[0, 0, 2], [5, 5, 2]], [[0, 0, -1], [5, 5, -1]])
    assert hit.body == box and hit.position[2] == pytest.approx(0.6)
    assert miss.body == -1
