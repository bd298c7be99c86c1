"""IK attempt functions are built once per chain and task in a process: a second solver of the
same chain reuses the function, another chain or mode gets its own, and answers do not depend
on what was built before."""

from __future__ import annotations

import numpy as np
import pytest

from bt_manip.kinematics import ArmModel, IKOptions, IKSolver, compiled, ik


@pytest.fixture
def built(monkeypatch: pytest.MonkeyPatch) -> list[tuple[int, str]]:
    """Empty memos; returns (nq, mode) of every attempt function built."""
    monkeypatch.setattr(ik, "_ATTEMPT_MEMO", {})
    monkeypatch.setattr(compiled, "_LIBRARY_MEMO", {})
    calls: list[tuple[int, str]] = []
    original = ik.attempt_function

    def counting(arm: ArmModel, mode: str, iterations: int, axis: str = "z") -> object:
        calls.append((arm.nq, mode))
        return original(arm, mode, iterations, axis)

    monkeypatch.setattr(ik, "attempt_function", counting)
    return calls


def _targets(arm: ArmModel, n: int = 5) -> list[np.ndarray]:
    rng = np.random.default_rng(4)
    return [arm.fk(rng.uniform(arm.lower, arm.upper)) for _ in range(n)]


def _answers(solver: IKSolver, targets: list[np.ndarray]) -> list[tuple[bool, bytes]]:
    out = []
    for t in targets:
        r = solver.solve(t)
        out.append((r.success, r.q.tobytes()))
    return out


def test_a_chain_builds_its_function_once_and_two_arms_do_not_share(
    built: list[tuple[int, str]], ur3: ArmModel, sawyer: ArmModel
) -> None:
    options = IKOptions(time_budget=None, max_restarts=20)
    first = IKSolver(ur3, options)
    IKSolver(sawyer, options)
    again = IKSolver(ur3, options)
    IKSolver(ur3, IKOptions(time_budget=None, free_axis="z"))
    assert built == [(6, "pose"), (7, "pose"), (6, "axis")]
    assert again._runner.function is first._runner.function
    assert again._runner.inputs[0] is not first._runner.inputs[0]  # buffers of its own
    ur3_targets, sawyer_targets = _targets(ur3), _targets(sawyer)
    assert _answers(again, ur3_targets) == _answers(first, ur3_targets)
    assert all(ok for ok, _ in _answers(IKSolver(sawyer, options), sawyer_targets))


def test_answers_with_remembered_functions_are_those_of_fresh_ones(
    built: list[tuple[int, str]], ur3: ArmModel, sawyer: ArmModel,
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    options = IKOptions(time_budget=None, max_restarts=20, posture_weight=0.2)
    targets = _targets(sawyer) + _targets(ur3)[:1]  # the UR3's pose is out of the Sawyer's reach
    IKSolver(ur3, options)
    remembered = _answers(IKSolver(sawyer, options), targets)
    monkeypatch.setattr(ik, "_ATTEMPT_MEMO", {})  # as in a fresh process
    monkeypatch.setattr(compiled, "_LIBRARY_MEMO", {})
    assert _answers(IKSolver(sawyer, options), targets) == remembered
    assert built == [(6, "pose"), (7, "pose"), (7, "pose")]


def test_memos_stay_bounded(built: list[tuple[int, str]], ur3: ArmModel) -> None:
    for iterations in range(1, ik._ATTEMPT_MEMO_SIZE + 6):
        IKSolver(ur3, IKOptions(iterations_per_attempt=iterations, compile=False))
    assert len(ik._ATTEMPT_MEMO) == ik._ATTEMPT_MEMO_SIZE
