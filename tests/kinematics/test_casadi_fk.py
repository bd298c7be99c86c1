"""The CasADi forward-kinematics graph against Pinocchio on random configurations."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

from bt_manip.kinematics import ArmModel
from bt_manip.kinematics.casadi_fk import fk_function, fk_graph

N_CONFIGURATIONS = 1000


@pytest.mark.parametrize("which", ["ur3", "sawyer", "composite"])
def test_casadi_fk_matches_pinocchio(which: str, request: pytest.FixtureRequest) -> None:
    arm: ArmModel = request.getfixturevalue(which)
    rng = np.random.default_rng(10)
    qs = np.stack([arm.random_configuration(rng) for _ in range(N_CONFIGURATIONS)], axis=1)
    batch = fk_function(arm).map(N_CONFIGURATIONS)
    poses, jacobians = (np.asarray(x) for x in batch(qs))
    worst_pose = worst_jac = 0.0
    for k in range(N_CONFIGURATIONS):
        q = qs[:, k]
        pose = poses[:, 4 * k : 4 * k + 4]
        jac = jacobians[:, arm.nq * k : arm.nq * (k + 1)]
        worst_pose = max(worst_pose, float(np.abs(pose - arm.fk(q)).max()))
        worst_jac = max(worst_jac, float(np.abs(jac - arm.jacobian(q)).max()))
    assert worst_pose < 1e-10
    assert worst_jac < 1e-10


def test_graph_is_differentiable(ur3: ArmModel) -> None:
    # Automatic differentiation of the graph's position agrees with the geometric Jacobian.
    g = fk_graph(ur3)
    d_pos = ca.Function("d", [g.q], [ca.jacobian(g.p, g.q)])
    rng = np.random.default_rng(11)
    for _ in range(20):
        q = ur3.random_configuration(rng)
        np.testing.assert_allclose(np.asarray(d_pos(q)), ur3.jacobian(q)[:3], atol=1e-12)


def test_axis_aligned_joints_give_a_small_graph(ur3: ArmModel) -> None:
    # Constant zeros and ones fold away: the whole 6-joint FK and Jacobian stay small.
    f = fk_function(ur3)
    assert f.n_instructions() < 600
