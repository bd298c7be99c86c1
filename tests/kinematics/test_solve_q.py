"""IKSolver.solve_q: the joints of a solve whose attempt from the seed succeeds, the same values
as solve() gives, and None whenever solve() would need restarts or fails."""

from __future__ import annotations

import numpy as np
import pytest

from bt_manip.kinematics import ArmModel, IKOptions, IKSolver

OPTIONS = IKOptions(time_budget=None, max_restarts=50, posture_weight=0.2)


@pytest.mark.parametrize("which", ["ur3", "sawyer"])
def test_solve_q_is_solve_when_the_seed_attempt_succeeds(
    which: str, request: pytest.FixtureRequest
) -> None:
    arm: ArmModel = request.getfixturevalue(which)
    solver = IKSolver(arm, OPTIONS)
    rng = np.random.default_rng(7)
    first_try = restarted = 0
    for _ in range(150):
        q_goal = arm.random_configuration(rng)
        near = np.clip(q_goal + rng.normal(scale=0.05, size=arm.nq), arm.lower, arm.upper)
        seed = near if rng.random() < 0.7 else arm.random_configuration(rng)
        target = arm.fk(q_goal)
        full = solver.solve(target, q_seed=seed)
        quick = solver.solve_q(target, seed)
        if full.success and full.restarts == 0:
            first_try += 1
            assert quick is not None and np.array_equal(quick, full.q)
        else:
            restarted += 1
            assert quick is None
    assert first_try > 50 and restarted > 0      # both cases were seen


def test_solve_q_gives_none_for_what_solve_rejects(ur3: ArmModel) -> None:
    solver = IKSolver(ur3, OPTIONS)
    far = np.eye(4)
    far[:3, 3] = ur3.shoulder() + np.array([2.0, 0.0, 0.0])
    skewed = np.eye(4)
    skewed[0, 1] = 0.5
    seed = ur3.mid.copy()
    for target in (far, skewed, np.full((4, 4), np.nan), np.eye(3)):
        assert not solver.solve(target, q_seed=seed).success
        assert solver.solve_q(target, seed) is None
    assert solver.solve_q(ur3.fk(seed), np.full(ur3.nq, np.nan)) is None
    assert np.array_equal(solver.solve_q(ur3.fk(seed), seed), solver.solve(ur3.fk(seed), seed).q)
