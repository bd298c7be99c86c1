"""The arm's allowed-collision matrix: found, written into the descriptor, read back, used."""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest

from bt_manip.errors import InputError
from bt_manip.manipulation.arm_planner import allowed_pairs
from bt_manip.manipulation.collision_scene import CollisionScene
from bt_manip.manipulation.self_collisions import find_allowed_collisions
from bt_manip.sim.robot_description import RobotDescription, load_description

ROOT = Path(__file__).resolve().parents[2]


def _tuck_scene(desc: RobotDescription, pairs: set[frozenset[str]]) -> CollisionScene:
    scene = CollisionScene(desc.urdf_path, list(desc.arm.joints))
    scene.allow(pairs)
    return scene


def test_husky_tuck_folds_the_arm_onto_itself_and_the_descriptor_allows_it() -> None:
    desc = RobotDescription.load("husky_ur3")
    tuck = np.asarray(desc.state("tuck"))
    bare = CollisionScene(desc.urdf_path, list(desc.arm.joints))
    touching = {frozenset(p) for p in bare.contacts(tuck)}
    assert frozenset(("ur3_forearm_link", "ur3_shoulder_link")) in touching
    listed = desc.planning.allowed
    assert listed is not None and touching <= listed["default"]
    assert not _tuck_scene(desc, allowed_pairs(desc)).collides(tuck)


@pytest.mark.parametrize("robot", ["husky_ur3", "sawyer", "panda", "omni_sawyer", "tiago"])
def test_every_shipped_descriptor_lists_what_robot_init_finds(robot: str) -> None:
    desc = RobotDescription.load(robot)
    found = find_allowed_collisions(desc)
    assert desc.planning.allowed == {"default": found.default, "never": found.never,
                                     "user": frozenset()}


def test_never_pairs_stay_apart_in_other_configurations() -> None:
    desc = RobotDescription.load("panda")
    listed = desc.planning.allowed
    assert listed is not None and not listed["default"] & listed["never"]
    scene = CollisionScene(desc.urdf_path, list(desc.arm.joints))
    rng = np.random.default_rng(11)  # other configurations than the 1000 that found them
    for _ in range(200):
        q = rng.uniform(scene.lower, scene.upper)
        assert not {frozenset(p) for p in scene.contacts(q)} & listed["never"]


def _copy(tmp_path: Path, name: str, tail: str) -> Path:
    """A copy of a shipped descriptor, its planning section replaced by ``tail``."""
    src = ROOT / "robots" / f"{name}.yaml"
    text = src.read_text()
    text = text[: text.index("planning:")] + tail
    out = tmp_path / f"{name}.yaml"
    out.write_text(text)
    for extra in ("sawyer.urdf",):
        if (ROOT / "robots" / extra).is_file():
            shutil.copy(ROOT / "robots" / extra, tmp_path / extra)
    return out


def test_listed_pairs_are_what_the_planner_leaves_out(tmp_path: Path) -> None:
    path = _copy(tmp_path, "sawyer", "planning:\n  padding: 0.05\n  allowed_collisions:\n"
                 "    user: [[right_l2, right_l6]]\n")
    desc = load_description(path)
    assert desc.planning.padding == 0.05
    assert allowed_pairs(desc) == {frozenset(("right_l2", "right_l6"))}


@pytest.mark.parametrize(("tail", "line", "message"), [
    ("planning:\n  padding: 0.5\n", 28, "planning.padding must be within 0..0.2, got 0.5"),
    ("planning:\n  allowed_collisions:\n    user: [[right_l2, nowhere]]\n", 28,
     "planning.allowed_collisions: no link 'nowhere' in the URDF"),
    ("planning:\n  allowed_collisions:\n    user: [[right_l2]]\n", 29,
     "each entry must be a pair of link names, got ['right_l2']"),
    ("planning:\n  allowed_collisions:\n    often: []\n", 29,
     "unknown key 'often' in planning.allowed_collisions"),
    ("planning:\n  srdf: missing.srdf\n", 28, "planning.srdf: no file"),
])
def test_bad_planning_sections_name_file_and_line(
    tmp_path: Path, tail: str, line: int, message: str
) -> None:
    path = _copy(tmp_path, "sawyer", tail)
    with pytest.raises(InputError) as err:
        load_description(path)
    text = str(err.value)
    assert f"{path}:{line}" in text and message in text


def test_a_continuous_joint_is_locked_at_its_angle() -> None:
    """The holonomic base's yaw is a continuous joint (cos, sin in Pinocchio): locked at 0.7
    rad it turns the arm by 0.7 rad, and leaves the arm's own links where they were."""
    import pinocchio as pin

    desc = RobotDescription.load("omni_sawyer")
    tuck = np.asarray(desc.state("tuck"))
    turned = CollisionScene(desc.urdf_path, list(desc.arm.joints),
                            locked={"base_yaw": 0.7}, allowed=allowed_pairs(desc))
    assert not turned.collides(tuck)
    data = turned.model.createData()
    pin.framesForwardKinematics(turned.model, data, tuck)
    base = data.oMf[turned.model.getFrameId("right_arm_base_link")].rotation
    assert np.arctan2(base[1, 0], base[0, 0]) == pytest.approx(0.7, abs=1e-9)
