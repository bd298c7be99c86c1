"""The arithmetic of arm moves that is worked out once per move (or per straight line) gives
the same numbers as the per-waypoint, per-tick numpy formulas it replaces: the turn between
two orientations, the joint speeds of a stage and the largest travel time."""

from __future__ import annotations

import math

import numpy as np
import pytest

from bt_manip.behaviours import cartesian
from bt_manip.behaviours.arm import CORRECTION_SPEED, MoveJoints, _largest
from bt_manip.behaviours.cartesian import _Turn


def _rotation(rng: np.random.Generator) -> np.ndarray:
    q, r = np.linalg.qr(rng.normal(size=(3, 3)))
    q = q @ np.diag(np.sign(np.diag(r)))
    return q if np.linalg.det(q) > 0 else -q


def _numpy_turn(ra: np.ndarray, rb: np.ndarray, s: float) -> np.ndarray:
    """The rotation a fraction s of the way from ra to rb, all in numpy (Rodrigues)."""
    rel = ra.T @ rb
    angle = cartesian._angle(ra, rb)
    if angle < 1e-9:
        return rb.copy()
    if np.pi - angle < 1e-6:
        w, v = np.linalg.eigh((rel + rel.T) / 2.0)
        axis = v[:, int(np.argmax(w))]
    else:
        axis = np.array([rel[2, 1] - rel[1, 2], rel[0, 2] - rel[2, 0], rel[1, 0] - rel[0, 1]])
        axis /= 2.0 * np.sin(angle)
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    a = angle * s
    result: np.ndarray = ra @ (np.eye(3) + np.sin(a) * k + (1.0 - np.cos(a)) * (k @ k))
    return result


def _about_z(angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def test_turn_fractions_equal_the_numpy_formula_bit_for_bit() -> None:
    rng = np.random.default_rng(3)
    pairs = [(_rotation(rng), _rotation(rng)) for _ in range(40)]
    down = np.diag([1.0, -1.0, -1.0])
    pairs += [(down, down @ _about_z(0.3)), (down, down.copy()), (np.eye(3), _about_z(math.pi))]
    for ra, rb in pairs:
        turn = _Turn(ra, rb)
        for s in (0.0, 0.05, 1 / 3, 0.5, 0.97, 1.0):
            assert np.array_equal(turn.at(s), _numpy_turn(ra, rb, s))


def test_turn_goes_evenly_from_start_to_goal() -> None:
    down = np.diag([1.0, -1.0, -1.0])
    goal = down @ _about_z(1.2)
    turn = _Turn(down, goal)
    assert turn.angle == pytest.approx(1.2)
    assert np.allclose(turn.at(0.0), down) and np.allclose(turn.at(1.0), goal)
    assert cartesian._angle(down, turn.at(0.25)) == pytest.approx(0.3)
    assert cartesian._angle(turn.at(0.25), goal) == pytest.approx(0.9)


class _Recorder:
    """Stands in for a robot: keeps what the move commanded."""

    def __init__(self) -> None:
        self.sent: list[tuple[np.ndarray, list[float]]] = []

    def set_arm_targets(self, q: np.ndarray, max_velocity: list[float]) -> None:
        self.sent.append((np.asarray(q), list(max_velocity)))


def _numpy_speeds(vmax: np.ndarray, joints: list[int], travel: np.ndarray, t: float) -> np.ndarray:
    floor = CORRECTION_SPEED * vmax
    speeds = floor.copy()
    if t > 1e-9:
        speeds[joints] = np.maximum(travel / t, floor[joints])
    else:
        speeds[joints] = vmax[joints]
    return speeds


@pytest.mark.parametrize("joints", [[0, 1, 2, 3, 4, 5, 6], [2], [1, 5], []])
def test_stage_speeds_equal_the_numpy_formula(joints: list[int]) -> None:
    rng = np.random.default_rng(len(joints))
    limits = rng.uniform(0.5, 2.5, size=7)
    speed = 0.37
    vmax = limits * speed
    move = MoveJoints.__new__(MoveJoints)
    move._vmax = vmax.tolist()
    move._floor = (CORRECTION_SPEED * vmax).tolist()
    for trial in range(20):
        q = rng.uniform(-2, 2, size=7)
        target = q + rng.uniform(-1, 1, size=7) * (trial % 4 != 0)  # some stages go nowhere
        travel = np.abs(target[joints] - q[joints])
        t = float(np.max(travel / vmax[joints])) if joints else 0.0
        q_list, target_list, vmax_list = q.tolist(), target.tolist(), vmax.tolist()
        travel_list = [abs(target_list[j] - q_list[j]) for j in joints]
        ratios = [d / vmax_list[j] for d, j in zip(travel_list, joints, strict=True)]
        assert (_largest(ratios) if joints else 0.0) == t
        robot = _Recorder()
        move.command = target
        move._send(robot, joints, travel_list, t)  # type: ignore[arg-type]
        assert robot.sent[0][1] == _numpy_speeds(vmax, joints, travel, t).tolist()


def test_largest_is_numpy_max_nan_included() -> None:
    assert _largest([0.5, 2.0, 1.0]) == 2.0
    assert _largest([0.0]) == 0.0
    assert math.isnan(_largest([1.0, math.nan, 3.0]))
    assert math.isnan(_largest([math.nan, 3.0]))
