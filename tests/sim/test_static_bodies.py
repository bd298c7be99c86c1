"""Walls, furniture and the ground are static rigid bodies whose collision shapes are still
known: the same numbers ``getCollisionShapeData`` gives for a multibody of the same shapes."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pybullet as pb
import pytest

from bt_manip.sim import pybullet_queries as pbq
from bt_manip.sim.fasteners import fasten, fastenings, structures_near
from bt_manip.sim.static_bodies import collision_data
from bt_manip.sim.world import World

WORLD = """
name: static_test
walls:
  - {name: wall_a, from: [0.0, 0.0], to: [4.0, 0.0], thickness: 0.15, height: 1.2,
     doors: [{at: 2.0, width: 0.9}]}
furniture:
  - name: rails
    pose: {xyz: [1.0, 1.0, 0.0], rpy: [0.0, 0.0, 0.3]}
    parts:
      - {shape: box, size: [1.1, 0.02, 0.03], xyz: [0.0, 0.023, 0.015]}
      - {shape: cylinder, radius: 0.04, height: 0.5, xyz: [0.3, 0.0, 0.25]}
  - {name: post, pose: [3.0, 1.0, 0.0], shape: box, size: [0.2, 0.2, 1.0]}
objects:
  - {name: crate, pose: [3.0, -1.0, 0.1], shape: box, size: [0.2, 0.2, 0.2], mass: 1.0}
"""


@pytest.fixture()
def world(tmp_path: Path) -> Iterator[World]:
    path = tmp_path / "world.yaml"
    path.write_text(WORLD)
    w = World(path, seed=0)
    yield w
    w.close()


def _twin_shapes(world: World, name: str) -> list[tuple]:
    """The collision shape data of a multibody with the shapes of static body ``name``, made
    in a client of its own from PyBullet's visual data (the same shapes, margins aside)."""
    c = pb.connect(pb.DIRECT)
    try:
        info = world.infos[name]
        visuals = pbq.visual_shapes(world.client, info.body_id)
        types = [v.geometry_type for v in visuals]
        col = pb.createCollisionShapeArray(
            types,
            halfExtents=[[d / 2 for d in v.dimensions] for v in visuals],
            radii=[v.dimensions[1] for v in visuals],
            lengths=[v.dimensions[0] for v in visuals],
            collisionFramePositions=[v.local_position for v in visuals],
            collisionFrameOrientations=[v.local_orientation for v in visuals],
            physicsClientId=c,
        )
        body = pb.createMultiBody(0, col, -1, [0, 0, 0], physicsClientId=c)
        return [(s[2], s[3], s[5], s[6]) for s in pb.getCollisionShapeData(body, -1,
                                                                           physicsClientId=c)]
    finally:
        pb.disconnect(c)


@pytest.mark.parametrize("name", ["wall_a", "rails", "post"])
def test_static_bodies_report_the_collision_shapes_of_a_multibody(world: World, name: str) -> None:
    body = world.infos[name].body_id
    with pytest.raises(pb.error):  # a rigid body: PyBullet itself gives no collision data
        pb.getCollisionShapeData(body, -1, physicsClientId=world.client)
    shapes = pbq.collision_shapes(world.client, body, -1)
    assert [(s.geometry_type, s.dimensions, s.local_position, s.local_orientation)
            for s in shapes] == _twin_shapes(world, name)
    assert all(s.body == body and s.link == -1 for s in shapes)
    assert pbq.collision_shapes(world.client, body, 0) == []


def test_thin_boxes_keep_pybullets_margin_rounding() -> None:
    # 0.01 m half extents come back as 0.020000000000000004: PyBullet takes its 4 cm collision
    # margin off and adds it back; the data must be PyBullet's, not the numbers asked for
    data = collision_data(False, {"shapeType": pb.GEOM_BOX, "halfExtents": [0.5, 0.01, 0.015]})
    c = pb.connect(pb.DIRECT)
    try:
        col = pb.createCollisionShape(pb.GEOM_BOX, halfExtents=[0.5, 0.01, 0.015],
                                      physicsClientId=c)
        body = pb.createMultiBody(0, col, -1, [0, 0, 0], physicsClientId=c)
        expected = pb.getCollisionShapeData(body, -1, physicsClientId=c)[0][3]
    finally:
        pb.disconnect(c)
    assert data[0].dimensions == expected
    assert data[0].dimensions[1] != 0.02


def test_the_ground_is_a_plane_and_movable_objects_stay_articulated(world: World) -> None:
    ground = pbq.collision_shapes(world.client, world.infos["ground"].body_id, -1)
    assert [s.geometry_type for s in ground] == [pb.GEOM_PLANE]
    crate = world.infos["crate"].body_id
    assert len(pb.getCollisionShapeData(crate, -1, physicsClientId=world.client)) == 1


def test_what_is_known_of_a_world_goes_with_it(world: World) -> None:
    client, post = world.client, world.infos["post"].body_id
    world.remove("post")
    assert (client, post) not in pbq._REGISTERED_SHAPES
    assert any(k[0] == client for k in pbq._REGISTERED_SHAPES)
    world.close()
    assert not any(k[0] == client for k in pbq._REGISTERED_SHAPES)


def test_an_object_fastened_to_a_wall_stays_where_it_was(world: World) -> None:
    crate = world.infos["crate"].body_id
    pb.resetBasePositionAndOrientation(crate, [1.0, 0.2, 0.6], [0, 0, 0, 1],
                                       physicsClientId=world.client)
    near = structures_near(world, crate, 0.2)
    assert near[0].name == "wall_a"
    fasten(world, crate, near[0])
    world.step(480)  # two seconds: unfastened it would have fallen half a metre
    pos, _ = pb.getBasePositionAndOrientation(crate, physicsClientId=world.client)
    assert pos == pytest.approx((1.0, 0.2, 0.6), abs=2e-3)
    assert fastenings(world) == {"crate": "wall_a"}


def test_the_hidden_client_is_reset_now_and_then_and_still_answers(
        monkeypatch: pytest.MonkeyPatch) -> None:
    import bt_manip.sim.static_bodies as sb

    first = collision_data(False, {"shapeType": pb.GEOM_SPHERE, "radius": 0.123})
    monkeypatch.setattr(sb._PROBE, "made", sb._PROBE_RESET_EVERY)
    again = collision_data(False, {"shapeType": pb.GEOM_SPHERE, "radius": 0.321})
    assert sb._PROBE.made == 1  # reset, then one shape made
    assert first[0].dimensions[0] == 0.123 and again[0].dimensions[0] == 0.321
