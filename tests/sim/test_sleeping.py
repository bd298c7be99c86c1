"""Movable objects at rest sleep (Bullet leaves them out of the solver), and still take part in
the physics: a body that runs into one wakes it, and removing what one rests on lets it fall."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pybullet as pb

from bt_manip.sim.world import World
from bt_manip.sim.world_spec import BodySpec, Part, Pose3D, Range2D

TABLE = Path(__file__).resolve().parents[2] / "worlds" / "sawyer_table.yaml"
EDGE = 0.1  # crate edge (m)


def _crate(name: str, x: float, y: float, z: float = EDGE / 2) -> BodySpec:
    return BodySpec(
        name=name, movable=True, parts=[Part("box", (EDGE, EDGE, EDGE))], urdf=None,
        pose=Pose3D((x, y, z)), planar=False, mass=1.0, friction=0.8,
        colour=(0.5, 0.3, 0.1, 1.0), randomize=Range2D(), line=0,
    )


def _speed(world: World, body: int) -> float:
    lin, ang = pb.getBaseVelocity(body, physicsClientId=world.client)
    return float(np.linalg.norm(lin) + np.linalg.norm(ang))


def test_a_resting_crate_sleeps_and_a_crate_running_into_it_wakes_it() -> None:
    with World(TABLE, seed=0) as world:
        resting = world.spawn(_crate("resting", 0.0, -1.5))
        world.step(round(3.0 * world.rate_hz))
        start = world.body_pose("resting").xyz
        assert _speed(world, resting) == 0.0  # asleep: Bullet zeroes a sleeping body's motion
        # the test pushes a second crate (the product never sets velocities) into the first
        mover = world.spawn(_crate("mover", -0.3, -1.5))
        pb.resetBaseVelocity(mover, [3.0, 0.0, 0.0], physicsClientId=world.client)
        world.step(round(2.0 * world.rate_hz))
        moved = world.body_pose("resting").xyz[0] - start[0]
        assert moved > 0.02, f"the crate run into moved {moved * 1000:.1f} mm"


def test_removing_what_a_sleeping_crate_rests_on_lets_it_fall() -> None:
    with World(TABLE, seed=0) as world:
        world.spawn(_crate("bottom", 0.0, -1.5))
        world.spawn(_crate("top", 0.0, -1.5, 1.5 * EDGE))
        world.step(round(3.0 * world.rate_hz))
        assert world.body_pose("top").xyz[2] > 1.4 * EDGE
        world.remove("bottom")
        world.step(round(1.0 * world.rate_hz))
        x, y, z = world.body_pose("top").xyz
        assert math.isclose(z, EDGE / 2, abs_tol=0.005), f"the top crate stays at z={z:.3f}"
        assert math.dist((x, y), (0.0, -1.5)) < 0.01
