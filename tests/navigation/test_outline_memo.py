"""Outlines of collision shapes remembered per process: what comes from memory is exactly what
a fresh computation gives, for other bands, frames, worlds and poses, and it cannot be
changed by a caller."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pybullet as pb
import pytest

from bt_manip.cache import Memo, bytes_key
from bt_manip.navigation import shapes
from bt_manip.navigation.shapes import Disc, Outline, Polygon, body_outlines
from bt_manip.sim.world import World

ROOT = Path(__file__).resolve().parents[2]


def _numbers(outlines: list[Outline]) -> list[bytes]:
    return [np.array([o.cx, o.cy, o.radius]).tobytes() if isinstance(o, Disc)
            else o.vertices.tobytes() for o in outlines]


def _fresh(*args: object, **kwargs: object) -> list[bytes]:
    shapes.OUTLINE_MEMO.clear()
    shapes.BODY_MEMO.clear()
    return _numbers(body_outlines(*args, **kwargs))  # type: ignore[arg-type]


@pytest.fixture()
def memos(monkeypatch: pytest.MonkeyPatch) -> Iterator[None]:
    """Memories of this test only (the process's own are left as they are)."""
    monkeypatch.setattr(shapes, "OUTLINE_MEMO", Memo(8192))
    monkeypatch.setattr(shapes, "BODY_MEMO", Memo(4096))
    yield


def test_remembered_outlines_equal_fresh_ones_across_worlds_bands_and_frames(memos: None) -> None:
    """Walls, furniture (boxes, cylinders), the panel and the robot's meshes of the house, in
    two seeds (the robot and panel elsewhere), in bands that differ in the last bits and in the
    robot's frame: outlined twice with the memories filling, then each fresh."""
    bands = [(0.02, 0.7299348376094262), (0.02, 0.7299348376094263), (0.3, 1.2)]
    outlined = 0
    for seed in (0, 7):
        with World(ROOT / "worlds" / "tb3_house.yaml", seed=seed) as world:
            robot = next(iter(world.robots.values()))
            c = world.client
            x, y, yaw = robot.base_pose2d()
            cases = [(b, band, f) for b in [i.body_id for i in world.infos.values()]
                     for band in bands for f in (None, shapes.planar_frame(x, y, yaw))]
            arm = robot.arm_link_ids()
            first = [_numbers(body_outlines(c, b, band, reference=f)) for b, band, f in cases]
            again = [_numbers(body_outlines(c, b, band, reference=f)) for b, band, f in cases]
            first_arm = _numbers(body_outlines(c, robot.body, bands[0], links=arm))
            fresh = [_fresh(c, b, band, reference=f) for b, band, f in cases]
            assert first == fresh
            assert again == fresh
            assert first_arm == _fresh(c, robot.body, bands[0], links=arm)
            outlined += sum(len(o) for o in fresh)
    assert outlined > 100  # walls, furniture, panel and robot all outlined


def test_bands_ending_on_at_and_around_the_heights_of_shapes_give_fresh_outlines(
    memos: None,
) -> None:
    """Upright and tilted boxes, upright and tilted cylinders and capsules, a compound of
    them: bands whose ends lie on the shapes' corner and end heights, a hair's breadth below
    or above them, or between them, outlined in one process equal each outline made fresh."""
    c = pb.connect(pb.DIRECT)
    try:
        bodies = []
        for yaw, tilt in ((0.0, 0.0), (0.7, 0.0), (np.pi / 2, 0.0), (0.3, 0.4)):
            quat = pb.getQuaternionFromEuler((tilt, 0.0, yaw))
            col = pb.createCollisionShape(pb.GEOM_BOX, halfExtents=(0.4, 0.1, 0.35),
                                          physicsClientId=c)
            bodies.append(pb.createMultiBody(0, col, -1, (1.0, 0.5, 0.35), quat,
                                             physicsClientId=c))
            for geom in (pb.GEOM_CYLINDER, pb.GEOM_CAPSULE):
                col = pb.createCollisionShape(geom, radius=0.2, height=0.6, physicsClientId=c)
                bodies.append(pb.createMultiBody(0, col, -1, (-1.0, 0.3, 0.5), quat,
                                                 physicsClientId=c))
        col = pb.createCollisionShapeArray(
            [pb.GEOM_BOX, pb.GEOM_CYLINDER], halfExtents=[[0.5, 0.5, 0.02], [0, 0, 0]],
            radii=[0, 0.04], lengths=[0, 0.7],
            collisionFramePositions=[[0, 0, 0.72], [0, 0, 0.35]], physicsClientId=c)
        bodies.append(pb.createMultiBody(0, col, -1, (3.0, 0.0, 0.0), physicsClientId=c))
        heights = [0.0, 0.02, 0.2, 0.35, 0.5, 0.7, 0.74, 0.8]
        ends = sorted({h + d for h in heights
                       for d in (0.0, 1e-12, -1e-12, 1e-17, -1e-17, 0.013)})
        ends.append(float(np.nextafter(0.7, 1.0)))
        bands = [(lo, hi) for lo in ends[::3] for hi in ends if hi > lo]
        got = [_numbers(body_outlines(c, b, band)) for band in bands for b in bodies]
        want = [_fresh(c, b, band) for band in bands for b in bodies]
        assert got == want
        assert len(shapes.BODY_MEMO) > 0
    finally:
        pb.disconnect(c)


def test_remembered_polygons_are_read_only(memos: None) -> None:
    c = pb.connect(pb.DIRECT)
    try:
        col = pb.createCollisionShape(pb.GEOM_BOX, halfExtents=(0.5, 0.2, 0.4), physicsClientId=c)
        body = pb.createMultiBody(0, col, -1, (1.0, 2.0, 0.4), physicsClientId=c)
        (first,) = body_outlines(c, body, (0.02, 1.0))
        (second,) = body_outlines(c, body, (0.02, 1.0))
        assert isinstance(first, Polygon) and second is first
        with pytest.raises(ValueError):
            first.vertices[0, 0] = 9.0
        assert first.extent() == pytest.approx((0.5, 1.8, 1.5, 2.2))
    finally:
        pb.disconnect(c)


def test_memories_are_bounded() -> None:
    memo: Memo[int] = Memo(5)
    for i in range(20):
        memo.put(i, i)
        assert len(memo) <= 5
    assert memo.get(19) == 19 and memo.get(0) is None
    memo.get(15)  # used last: kept when the next is added
    memo.put(20, 20)
    assert memo.get(15) == 15 and memo.get(16) is None


def test_long_keys_are_digests_and_short_ones_stay_apart_from_them() -> None:
    long_a, long_b = b"x" * 1000, b"x" * 999 + b"y"
    assert bytes_key(long_a) == bytes_key(b"x" * 1000) != bytes_key(long_b)
    assert len(bytes_key(long_a)) == 33
    digest = bytes_key(long_a)
    assert bytes_key(digest[1:]) != digest and bytes_key(digest) != digest  # kinds never meet
    assert bytes_key(b"") != bytes_key(b"\x00")
