"""The turn of a straight-line move, worked out once per line, gives the same rotations as the
per-waypoint numpy formula it replaces (Rodrigues), bit for bit."""

from __future__ import annotations

import math

import numpy as np
import pytest

from bt_manip.manipulation import cartesian
from bt_manip.manipulation.cartesian import _Turn


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
