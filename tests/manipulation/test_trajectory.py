"""A planned path's timing: on its segments, within the joints' velocity and acceleration limits."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from bt_manip.manipulation.trajectory import time_parameterise

VMAX = np.array([1.0, 0.5, 2.0])
AMAX = np.array([2.0, 1.0, 4.0])


def _samples(path: np.ndarray, dt: float = 1e-3) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    traj = time_parameterise(path, VMAX, AMAX)
    times = np.arange(0.0, traj.duration + dt, dt)
    q = np.array([traj.position(t) for t in times])
    v = np.array([traj.velocity(t) for t in times])
    return times, q, v


def _distance_to_path(p: np.ndarray, path: np.ndarray) -> float:
    best = np.inf
    for a, b in itertools.pairwise(path):
        d = b - a
        s = np.clip((p - a) @ d / (d @ d), 0.0, 1.0)
        best = min(best, float(np.linalg.norm(a + s * d - p)))
    return best


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_random_paths_keep_to_their_segments_and_the_limits(seed: int) -> None:
    rng = np.random.default_rng(seed)
    path = np.cumsum(rng.uniform(-1.0, 1.0, (5, 3)), axis=0)
    times, q, v = _samples(path)
    assert np.allclose(q[0], path[0]) and np.allclose(q[-1], path[-1])
    assert np.allclose(v[0], 0.0) and np.allclose(v[-1], 0.0)
    assert max(_distance_to_path(p, path) for p in q) < 1e-9
    assert np.all(np.abs(v) <= VMAX * (1 + 1e-9))
    accel = np.diff(v, axis=0) / np.diff(times)[:, None]
    assert np.all(np.abs(accel) <= AMAX * (1 + 1e-6))
    # finite differences of the positions are the velocities it reports
    assert np.allclose(np.diff(q, axis=0) / np.diff(times)[:, None], v[:-1], atol=5e-3)


def test_the_arm_stops_at_a_corner_and_runs_on_through_a_straight_waypoint() -> None:
    corner = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 0.5, 0.0]])
    traj = time_parameterise(corner, VMAX, AMAX)
    t_corner = traj.pieces[1].t0
    assert np.allclose(traj.velocity(t_corner), 0.0)
    straight = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [3.0, 0.0, 0.0]])
    one = time_parameterise(straight, VMAX, AMAX)
    assert len(one.pieces) == 1 and one.velocity(1.0)[0] == pytest.approx(1.0)


def test_a_long_move_reaches_top_speed_and_a_short_one_does_not() -> None:
    long = time_parameterise(np.array([[0.0, 0, 0], [0.0, 0.0, 10.0]]), VMAX, AMAX)
    # joint 2 alone: 2 rad/s top speed reached after 0.5 s; 10 rad in 10/2 + 0.5 s
    assert long.duration == pytest.approx(5.5)
    short = time_parameterise(np.array([[0.0, 0, 0], [0.0, 0.0, 0.25]]), VMAX, AMAX)
    # a triangle: 0.125 rad each way at 4 rad/s^2 -> 0.25 s each way
    assert short.duration == pytest.approx(0.5)
    assert max(abs(short.velocity(t)[2]) for t in np.linspace(0, 0.5, 101)) < 2.0


def test_joints_move_in_proportion_so_the_slowest_sets_the_pace() -> None:
    traj = time_parameterise(np.array([[0.0, 0, 0], [1.0, 1.0, 1.0]]), VMAX, AMAX)
    # joint 1 (0.5 rad/s, 1 rad/s^2) limits every joint: 1/0.5 + 0.5 = 2.5 s
    assert traj.duration == pytest.approx(2.5)
    v = traj.velocity(1.25)
    assert v == pytest.approx([0.5, 0.5, 0.5])


def test_bad_limits_are_refused() -> None:
    with pytest.raises(ValueError, match="> 0"):
        time_parameterise([[0.0, 0, 0], [1.0, 0, 0]], [1.0, 0.0, 1.0], AMAX)
    with pytest.raises(ValueError, match="one velocity"):
        time_parameterise([[0.0, 0], [1.0, 0]], VMAX, AMAX)
