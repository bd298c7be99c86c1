"""The two reference worlds: loading, rest, determinism, randomisation, named poses."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from bt_manip.sim.world import World

ROOT = Path(__file__).resolve().parents[2]
HOUSE = ROOT / "worlds" / "tb3_house.yaml"
TABLE = ROOT / "worlds" / "sawyer_table.yaml"


@pytest.mark.parametrize(
    ("path", "robot", "description", "n_objects", "n_models"),
    [(HOUSE, "husky", "husky_ur3", 1, 0), (TABLE, "sawyer", "sawyer", 0, 10)],
)
def test_world_loads_with_its_robot(
    path: Path, robot: str, description: str, n_objects: int, n_models: int
) -> None:
    with World(path, seed=0) as world:
        assert list(world.robots) == [robot]
        assert world.robots[robot].description.name == description
        assert len(world.movable) == n_objects
        assert len(world.models) == n_models
        assert world.obstacle_body_ids()


def _table_with_blocks(seed: int) -> World:
    """The table world with its ten block models spawned."""
    world = World(TABLE, seed=seed)
    for name in sorted(world.models):
        world.spawn_model(name)
    return world


@pytest.mark.parametrize("path", [HOUSE, TABLE], ids=["house", "table"])
def test_ten_seconds_with_no_commands_leaves_everything_at_rest(path: Path) -> None:
    with _table_with_blocks(3) if path == TABLE else World(path, seed=3) as world:
        before = world.snapshot()
        world.step(round(10.0 * world.rate_hz))
        after = world.snapshot()
        assert world.time == pytest.approx(10.0)
        for name in before:
            if name == "time":
                continue
            drift = math.dist(before[name]["pos"], after[name]["pos"])
            assert drift < 1e-3, f"{name} drifted {drift * 1000:.3f} mm"
            assert np.linalg.norm(after[name]["lin"]) < 1e-2, f"{name} still moving"
            q0 = np.array([j[0] for j in before[name]["joints"]])
            q1 = np.array([j[0] for j in after[name]["joints"]])
            if name in world.robots:
                arm = world.robots[name].description.arm.joints
                idx = [world.robots[name].joint_index(j) for j in arm]
                assert np.max(np.abs(q1[idx] - q0[idx])) < 1e-3, f"{name} arm sagged"


def _run(path: Path, seed: int) -> dict:
    with World(path, seed=seed) as world:
        for robot in world.robots.values():
            if robot.description.base.type == "skid_steer":
                robot.set_wheel_velocities(3.0, 2.0)
        world.step(480)
        return world.snapshot()


def test_same_seed_gives_identical_final_state() -> None:
    assert _run(HOUSE, 7) == _run(HOUSE, 7)


def test_different_seeds_give_different_starts_within_ranges() -> None:
    starts = {}
    for seed in (1, 2):
        with World(HOUSE, seed=seed) as world:
            starts[seed] = world.robots["husky"].base_pose2d()
        with _table_with_blocks(seed) as world:
            blocks = {n: world.body_pose(n).xyz for n in world.movable}
        assert len(blocks) == 10
        nominal = {b.name: b.pose.xyz for b in world.spec.models}
        for name, xyz in blocks.items():
            assert abs(xyz[0] - nominal[name][0]) <= 0.01 + 1e-9
            assert abs(xyz[1] - nominal[name][1]) <= 0.01 + 1e-9
    assert starts[1] != starts[2]
    for x, y, yaw in starts.values():
        assert -1.3 - 1e-6 <= x <= -0.7 + 1e-6
        assert 2.7 - 1e-6 <= y <= 3.3 + 1e-6
        assert -0.5 - 1e-3 <= yaw <= 0.5 + 1e-3


def test_house_named_poses_and_doorways() -> None:
    with World(HOUSE, seed=0) as world:
        pre = world.poses["pregrasp_panel"]
        goal = world.poses["goal"]
        assert (pre.x, pre.y) == (0.595, -0.302)
        assert pre.yaw == pytest.approx(2 * math.atan2(-0.441, 0.898))
        assert (goal.x, goal.y) == (2.616, -0.715)
        assert goal.yaw == pytest.approx(2 * math.atan2(0.411, 0.912))
        doors = [d for w in world.spec.walls for d in w.doors]
        assert len(doors) >= 6
        assert min(d.width for d in doors) >= 1.0
        xs = [c for w in world.spec.walls for c in (w.start[0], w.end[0])]
        ys = [c for w in world.spec.walls for c in (w.start[1], w.end[1])]
        assert max(xs) - min(xs) == pytest.approx(15.0)
        assert max(ys) - min(ys) == pytest.approx(10.15)


def test_sim_clock_follows_steps() -> None:
    with World(TABLE, seed=0) as world:
        world.step(12)
        assert world.clock.now() == pytest.approx(12 / 240)
        assert world.step_count == 12


def test_solver_tolerance_is_read_and_bounded(tmp_path: Path) -> None:
    from bt_manip.errors import InputError
    from bt_manip.sim.world_reader import parse_world

    ok = tmp_path / "ok.yaml"
    ok.write_text("name: ok\nphysics: {solver_tolerance: 0.01}\n")
    assert parse_world(ok).physics.solver_tolerance == 0.01
    plain = tmp_path / "plain.yaml"
    plain.write_text("name: plain\n")
    assert parse_world(plain).physics.solver_tolerance is None  # PyBullet's own
    bad = tmp_path / "bad.yaml"
    bad.write_text("name: bad\nphysics:\n  solver_tolerance: 5\n")
    with pytest.raises(InputError) as err:
        parse_world(bad)
    assert f"{bad}:3: physics.solver_tolerance must be within 0..1, got 5" in str(err.value)
