"""The reach search: the tilt's direction and size, the order candidates are tried in, and a
configuration the caller refuses counting as not reached."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from bt_manip.geometry import rotation_matrix
from bt_manip.manipulation.reach import ReachOptions, UnreachableError, first_reached, tilted
from bt_manip.run.context import RunContext
from bt_manip.sim.world import World

ROOT = Path(__file__).resolve().parents[2]
DOWN = rotation_matrix([0.0, 1.0, 0.0, 0.0])


def test_the_tilt_leans_the_tool_axis_away_from_the_base_by_the_angle() -> None:
    base = np.array([0.0, 0.0, 0.9])
    for point in (np.array([1.0, 0.0, 0.9]), np.array([0.6, -0.8, 0.5])):
        out = (point[:2] - base[:2]) / np.linalg.norm(point[:2] - base[:2])
        for deg in (10.0, 30.0):
            turned = tilted(DOWN, point, base, math.radians(deg))
            assert np.allclose(turned.T @ turned, np.eye(3)) and np.linalg.det(turned) > 0
            axis = turned[:, 2]
            assert math.degrees(math.acos(-axis[2])) == pytest.approx(deg)
            assert axis[:2] @ out == pytest.approx(math.sin(math.radians(deg)))
    # no tilt: the rotation as given; straight above the base: along world x
    assert np.array_equal(tilted(DOWN, base, base, 0.0), DOWN)
    assert tilted(DOWN, base, base, math.radians(20))[0, 2] == pytest.approx(
        math.sin(math.radians(20)))


def test_the_tilts_tried_run_from_none_to_the_cone_in_even_steps() -> None:
    assert ReachOptions(math.radians(25), 5).tilts() == pytest.approx(
        [math.radians(d) for d in (0, 5, 10, 15, 20, 25)])
    assert ReachOptions(0.0).tilts() == [0.0]
    with pytest.raises(ValueError, match="max_tilt"):
        ReachOptions(math.radians(100))
    with pytest.raises(ValueError, match="tilt_steps"):
        ReachOptions(0.1, 0)


def test_candidates_are_tried_in_order_and_a_refused_one_is_not_reached() -> None:
    with World(ROOT / "worlds" / "sawyer_table.yaml", seed=0) as world:
        robot = world.robots["sawyer"]
        services = RunContext.for_world(world).robot_services("sawyer")
        tip = robot.description.grasp_frame
        seed = robot.arm_positions()
        points = [np.array([1.6, 0.0, 0.9]), np.array([0.7, -0.2, 0.95]),
                  np.array([0.75, -0.25, 0.95])]
        options = ReachOptions(math.radians(20), 2)
        reached = first_reached(services, tip, points, DOWN, seed, options)
        assert reached.index == 1 and reached.tilt == 0.0
        assert np.array_equal(reached.rotation, DOWN)
        seen: list[np.ndarray] = []

        def refuse_first(q: np.ndarray) -> str | None:
            seen.append(q)
            return "touches the bin" if len(seen) == 1 else None

        assert first_reached(services, tip, points, DOWN, seed, options,
                             refuse_first).index == 2
        with pytest.raises(UnreachableError) as err:
            first_reached(services, tip, points, DOWN, seed, options, lambda q: "in the way",
                          lambda i: f"spot {i}")
        text = str(err.value)
        assert text.startswith("no candidate is reached with the tool within 20 deg of the "
                               "requested orientation: spot 0: beyond reach: target")
        assert text.endswith("; reached but refused: spot 1 tilted 0 deg: in the way")
