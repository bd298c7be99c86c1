"""Planning scenes of URDFs as real robots write them: continuous arm joints (PR2, Kinova) and
joints named like a link (ANYmal C, SO-100), checked against the same robot written without
them."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from bt_manip.manipulation.collision_scene import CollisionScene, Obstacle

BOX = '<collision><geometry><box size="{x} {y} {z}"/></geometry></collision>'


def _arm(path: Path, first: str = "revolute", names: tuple[str, str] = ("j1", "j2"),
         tool_joint: str = "tool_fix") -> Path:
    """A base, a 0.6 m upper arm turning about z, a 0.5 m forearm bending about y, a tool
    fixed at its end; ``first`` is the first joint's type, ``names`` the arm joints'."""
    limit = '<limit lower="-3.14159265" upper="3.14159265" effort="1" velocity="1"/>'
    tool = tool_joint if tool_joint != "tool_fix" else "tool"
    tool_box = BOX.format(x=0.05, y=0.05, z=0.05)
    path.write_text(f"""<robot name="arm">
  <link name="base">{BOX.format(x=0.3, y=0.3, z=0.1)}</link>
  <link name="upper">
    <collision><origin xyz="0.3 0 0"/><geometry><box size="0.6 0.08 0.08"/></geometry></collision>
  </link>
  <link name="fore">
    <collision><origin xyz="0.25 0 0"/><geometry><box size="0.5 0.06 0.06"/></geometry></collision>
  </link>
  <link name="{tool}">{tool_box}</link>
  <joint name="{names[0]}" type="{first}"><parent link="base"/><child link="upper"/>
    <origin xyz="0 0 0.2"/><axis xyz="0 0 1"/>{limit if first == "revolute" else ""}</joint>
  <joint name="{names[1]}" type="revolute"><parent link="upper"/><child link="fore"/>
    <origin xyz="0.6 0 0"/><axis xyz="0 1 0"/>{limit}</joint>
  <joint name="{tool_joint}" type="fixed"><parent link="fore"/>
    <child link="{tool}"/>
    <origin xyz="0.5 0 0"/></joint>
</robot>
""")
    return path


WALL = Obstacle("wall", "box", (0.1, 2.0, 1.0), ((1, 0, 0, 0.8), (0, 1, 0, 0), (0, 0, 1, 0.5),
                                                  (0, 0, 0, 1)))


def _agree(a: CollisionScene, b: CollisionScene, seed: int,
           names: dict[str, str] | None = None) -> int:
    """Both scenes answer alike on random configurations (``names``: ``a``'s link names as
    ``b`` calls them); how many collided."""
    rename = names or {}
    rng = np.random.default_rng(seed)
    hits = 0
    for _ in range(150):
        q = rng.uniform(-math.pi, math.pi, 2)
        assert a.collides(q) == b.collides(q), q
        assert [tuple(rename.get(n, n) for n in pair) for pair in a.contacts(q)] == b.contacts(q)
        hits += a.collides(q)
    return hits


def test_a_continuous_joint_plans_as_a_revolute_one_within_a_turn(tmp_path: Path) -> None:
    turning = CollisionScene(_arm(tmp_path / "turning.urdf", "continuous"), ["j1", "j2"])
    limited = CollisionScene(_arm(tmp_path / "limited.urdf"), ["j1", "j2"])
    assert turning.model.nq == 3 and limited.model.nq == 2  # (cos, sin) of j1
    assert turning.lower == pytest.approx([-math.pi, -math.pi])
    assert turning.upper == pytest.approx([math.pi, math.pi])
    assert turning.pin_q(np.array([math.pi / 2, 0.3])) == pytest.approx([0.0, 1.0, 0.3])
    for scene in (turning, limited):
        scene.add_obstacles([WALL])
    hits = _agree(turning, limited, seed=3)
    assert 15 < hits < 135  # the wall is met from some headings only
    free, blocked = np.array([math.pi, 0.0]), np.array([0.0, 0.0])
    assert not turning.collides(free) and turning.collides(blocked)
    assert turning.segment_free(free, np.array([math.pi / 2, 0.0]), 0.05)
    assert not turning.segment_free(free, blocked, 0.05)


def test_joints_named_like_links_keep_their_names(tmp_path: Path) -> None:
    clashing = _arm(tmp_path / "clash.urdf", names=("upper", "fore"), tool_joint="toolframe")
    scene = CollisionScene(clashing, ["upper", "fore"])
    assert scene.joint_names == ("upper", "fore")
    plain = CollisionScene(_arm(tmp_path / "plain.urdf"), ["j1", "j2"])
    for s in (scene, plain):
        s.add_obstacles([WALL])
    assert _agree(scene, plain, seed=5, names={"toolframe": "tool"}) > 0
    # the first joint locked: Pinocchio's reduction meets the name twice there too
    locked = CollisionScene(clashing, ["fore"], locked={"upper": math.pi})
    assert locked.joint_names == ("fore",)
    locked.add_obstacles([WALL])
    assert not locked.collides(np.array([0.0]))
