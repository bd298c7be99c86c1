"""The arithmetic of arm moves that is worked out once per move gives the same numbers as the
per-tick numpy formulas it replaces: the joint speeds of a stage and the largest travel time
(the turn of a straight line: tests/manipulation/test_cartesian.py)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from bt_manip.behaviours.arm import CORRECTION_SPEED, MoveJoints, _largest


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
