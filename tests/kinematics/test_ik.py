"""IKSolver: solutions within limits and tolerance, partial targets, posture, failure reasons."""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest
from kin_helpers import pose_errors

from bt_manip.kinematics import ArmModel, IKOptions, IKSolver
from bt_manip.kinematics.compiled import CompiledRunner, load_runner
from bt_manip.kinematics.reasons import wrap_into_limits
from bt_manip.kinematics.solver_graph import attempt_function
from bt_manip.sim.assets import ur3_urdf

DETERMINISTIC = IKOptions(time_budget=None)


def random_targets(arm: ArmModel, n: int, seed: int) -> list[tuple[np.ndarray, np.ndarray]]:
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(n):
        q = arm.random_configuration(rng)
        out.append((q, arm.fk(q)))
    return out


@pytest.mark.parametrize("which", ["ur3", "sawyer", "composite"])
def test_reachable_targets_are_solved_within_limits_and_tolerance(
    which: str, request: pytest.FixtureRequest
) -> None:
    arm: ArmModel = request.getfixturevalue(which)
    solver = IKSolver(arm, DETERMINISTIC)
    solved = 0
    targets = random_targets(arm, 200, seed=20)
    for _, target in targets:
        res = solver.solve(target)
        assert res.q.shape == (arm.nq,)
        assert arm.within_limits(res.q), res.q
        if res.success:
            solved += 1
            assert res.reason is None
            dp, dr = pose_errors(arm, res.q, target)
            assert dp <= 1e-5 and dr <= 1e-5
            assert res.position_error <= np.sqrt(3) * 1e-5
            assert res.iterations >= 1
        else:
            assert res.reason
    assert solved >= 198, f"{solved}/200 solved"


def test_beyond_reach_fails_before_iterating(ur3: ArmModel) -> None:
    solver = IKSolver(ur3)
    target = np.eye(4)
    target[:3, 3] = ur3.shoulder() + np.array([2.0, 0.0, 0.0])
    res = solver.solve(target)
    assert not res.success
    assert res.reason is not None
    assert res.reason.startswith("beyond reach: target 2.00 m from the shoulder, reach 0.59 m")
    # Rejected by the reach bound, before any solver iteration or restart.
    assert res.iterations == 0
    assert res.restarts == 0
    assert ur3.within_limits(res.q)


def test_same_seed_and_target_give_the_same_answer(ur3: ArmModel) -> None:
    first = IKSolver(ur3, DETERMINISTIC)
    second = IKSolver(ur3, DETERMINISTIC)
    restarted = 0
    for _, target in random_targets(ur3, 40, seed=21):
        a = first.solve(target)
        b = second.solve(target)
        again = first.solve(target)
        assert np.array_equal(a.q, b.q) and np.array_equal(a.q, again.q)
        assert (a.restarts, a.iterations) == (b.restarts, b.iterations)
        restarted += a.restarts > 0
    assert restarted > 0  # the random restarts are covered too


def test_a_different_restart_seed_changes_only_restarted_answers(ur3: ArmModel) -> None:
    base = IKSolver(ur3, DETERMINISTIC)
    other = IKSolver(ur3, IKOptions(time_budget=None, seed=7))
    for _, target in random_targets(ur3, 30, seed=22):
        a, b = base.solve(target), other.solve(target)
        if a.restarts == 0:
            assert np.array_equal(a.q, b.q)


def test_seed_near_a_solution_stays_on_that_branch(ur3: ArmModel) -> None:
    solver = IKSolver(ur3, DETERMINISTIC)
    rng = np.random.default_rng(23)
    for q_true, target in random_targets(ur3, 30, seed=24):
        seed = np.clip(q_true + rng.normal(0.0, 0.02, ur3.nq), ur3.lower, ur3.upper)
        res = solver.solve(target, q_seed=seed)
        assert res.success and res.restarts == 0
        wrapped = wrap_into_limits(ur3, res.q)
        # Other IK branches lie O(1) rad away; near a singularity the same branch may still
        # differ by a few mrad within the pose tolerance.
        assert np.abs(np.angle(np.exp(1j * (wrapped - q_true)))).max() < 0.05


@pytest.mark.parametrize("free_axis", [None, "z"])
def test_seed_half_a_turn_away_is_not_mistaken_for_a_solution(
    ur3: ArmModel, free_axis: str | None
) -> None:
    # From a seed whose tool frame is the target's turned by 180 degrees about x, the skew
    # part of the rotation error vanishes; the solver must still see the half turn.
    plain = IKSolver(ur3, DETERMINISTIC)
    solver = IKSolver(ur3, IKOptions(time_budget=None, free_axis=free_axis))
    checked = 0
    for _, target in random_targets(ur3, 12, seed=41):
        flipped = target.copy()
        flipped[:3, :3] = target[:3, :3] @ np.diag([1.0, -1.0, -1.0])
        seed = plain.solve(flipped)
        if not seed.success:
            continue
        res = solver.solve(target, q_seed=seed.q)
        assert res.success
        assert res.iterations > 0
        pose = ur3.fk(res.q)
        assert np.abs(pose[:3, 2] - target[:3, 2]).max() < 1e-4
        checked += 1
    assert checked >= 5


def test_seed_outside_limits_is_brought_inside(ur3: ArmModel) -> None:
    q_true, target = random_targets(ur3, 1, seed=25)[0]
    seed = q_true.copy()
    seed[2] = 5.0  # elbow limits are +-pi
    res = IKSolver(ur3, DETERMINISTIC).solve(target, q_seed=seed)
    assert res.success and ur3.within_limits(res.q)


@pytest.fixture(scope="module")
def ur3_tight_wrist(tmp_path_factory: pytest.TempPathFactory) -> ArmModel:
    """The UR3 with wrist_3 limited to [0, 0.5] rad."""
    text = ur3_urdf().read_text()
    start = text.index('<joint name="wrist_3_joint"')
    end = text.index("</joint>", start)
    joint = text[start:end].replace(
        'lower="-6.28318530718" upper="6.28318530718"', 'lower="0.0" upper="0.5"'
    )
    assert joint != text[start:end]
    path = tmp_path_factory.mktemp("ur3") / "ur3_tight.urdf"
    path.write_text(text[:start] + joint + text[end:])
    return ArmModel.from_urdf(path)


def test_joint_limits_reason_names_the_joint(ur3: ArmModel, ur3_tight_wrist: ArmModel) -> None:
    target = ur3.fk(np.array([0.3, -1.2, 0.4, -0.5, 1.2, 2.0]))
    res = IKSolver(ur3_tight_wrist, IKOptions(time_budget=None, max_restarts=30)).solve(target)
    assert not res.success
    assert res.reason is not None
    assert res.reason.startswith("joint limits: the solutions found need wrist_3_joint at 2.00 rad")
    assert "(limits 0.00 .. 0.50)" in res.reason
    assert ur3_tight_wrist.within_limits(res.q)
    assert res.restarts == 30


def test_a_diagnosis_leaves_the_limits_loaded(ur3: ArmModel, ur3_tight_wrist: ArmModel) -> None:
    options = IKOptions(time_budget=None, max_restarts=30)
    used, fresh = IKSolver(ur3_tight_wrist, options), IKSolver(ur3_tight_wrist, options)
    beyond = ur3.fk(np.array([0.3, -1.2, 0.4, -0.5, 1.2, 2.0]))  # wrist beyond its limits
    first_reason = used.solve(beyond).reason
    again = used.solve(beyond)                 # the limits are back: fails the same way
    assert not again.success and again.reason == first_reason
    assert used.solve_q(beyond, ur3_tight_wrist.mid) is None
    reachable = ur3.fk(np.array([0.3, -1.2, 0.4, -0.5, 1.2, 0.25]))
    after, first = used.solve(reachable), fresh.solve(reachable)
    assert after.success and np.array_equal(after.q, first.q)
    assert ur3_tight_wrist.within_limits(after.q)


def test_not_converged_reason_gives_the_best_error(ur3: ArmModel) -> None:
    options = IKOptions(time_budget=None, max_restarts=2, iterations_per_attempt=2)
    _, target = random_targets(ur3, 1, seed=26)[0]
    res = IKSolver(ur3, options).solve(target)
    assert not res.success
    assert res.reason is not None
    assert res.reason.startswith("not converged in the budget (2 restarts, 6 iterations")
    assert f"best error {res.position_error * 1e3:.2f} mm" in res.reason
    assert res.position_error > 1e-5


def test_time_budget_stops_the_restarts(ur3: ArmModel) -> None:
    options = IKOptions(time_budget=1e-9, iterations_per_attempt=2, diagnose=False)
    _, target = random_targets(ur3, 1, seed=26)[0]
    res = IKSolver(ur3, options).solve(target)
    assert not res.success
    assert res.restarts == 0  # the budget is checked after each attempt
    assert res.reason is not None
    assert "time budget of 0.0 ms spent" in res.reason


def test_position_only_target(ur3: ArmModel) -> None:
    solver = IKSolver(ur3, IKOptions(time_budget=None, position_only=True))
    for _, target in random_targets(ur3, 30, seed=27):
        target[:3, :3] = np.eye(3)  # ignored
        res = solver.solve(target)
        assert res.success
        assert np.abs(ur3.fk(res.q)[:3, 3] - target[:3, 3]).max() <= 1e-5
        assert res.rotation_error == 0.0


def test_top_down_grasp_with_free_yaw(ur3: ArmModel) -> None:
    solver = IKSolver(ur3, IKOptions(time_budget=None, free_axis="z"))
    rng = np.random.default_rng(28)
    yaws = []
    for _ in range(20):
        yaw = rng.uniform(-np.pi, np.pi)
        c, s = np.cos(yaw), np.sin(yaw)
        target = np.eye(4)
        # Tool z pointing down, tool x at the given yaw.
        target[:3, :3] = np.array([[c, s, 0.0], [s, -c, 0.0], [0.0, 0.0, -1.0]])
        target[:3, 3] = [rng.uniform(0.15, 0.35), rng.uniform(-0.2, 0.2), rng.uniform(0.0, 0.2)]
        res = solver.solve(target)
        assert res.success, res.reason
        pose = ur3.fk(res.q)
        assert np.abs(pose[:3, 3] - target[:3, 3]).max() <= 1e-5
        angle = np.arccos(np.clip(pose[:3, 2] @ np.array([0.0, 0.0, -1.0]), -1.0, 1.0))
        assert angle <= 1e-5
        assert res.rotation_error <= 1e-5
        yaws.append(np.arctan2(pose[1, 0], pose[0, 0]) - yaw)
    # Yaw is free: the solver does not bother matching it.
    assert np.abs(np.angle(np.exp(1j * np.array(yaws)))).max() > 1e-3


def test_posture_cost_keeps_a_redundant_arm_near_the_seed(sawyer: ArmModel) -> None:
    plain = IKSolver(sawyer, DETERMINISTIC)
    posture = IKSolver(sawyer, IKOptions(time_budget=None, posture_weight=0.3))
    rng = np.random.default_rng(29)
    closer = 0
    total_plain = total_posture = 0.0
    targets = random_targets(sawyer, 30, seed=30)
    for q_true, target in targets:
        seed = np.clip(q_true + rng.normal(0.0, 0.3, sawyer.nq), sawyer.lower, sawyer.upper)
        a, b = plain.solve(target, seed), posture.solve(target, seed)
        assert a.success and b.success
        dp, dr = pose_errors(sawyer, b.q, target)
        assert dp <= 1e-5 and dr <= 1e-5
        if a.restarts or b.restarts:
            continue
        da, db = np.linalg.norm(a.q - seed), np.linalg.norm(b.q - seed)
        total_plain += da
        total_posture += db
        closer += db <= da + 1e-9
    assert closer >= 20
    assert total_posture < total_plain


def test_invalid_targets_fail_with_a_reason(ur3: ArmModel) -> None:
    solver = IKSolver(ur3)
    nan = np.full((4, 4), np.nan)
    skewed = np.eye(4)
    skewed[0, 1] = 0.5
    mirrored = np.diag([1.0, 1.0, -1.0, 1.0])
    for bad in (nan, skewed, mirrored, np.eye(3)):
        res = solver.solve(bad)
        assert not res.success
        assert res.reason is not None and res.reason.startswith("invalid target")
    for seed in (np.zeros(3), np.full(6, np.nan)):
        res = solver.solve(np.eye(4), q_seed=seed)
        assert res.reason is not None and res.reason.startswith("invalid seed")
        assert ur3.within_limits(res.q)


def test_options_are_validated() -> None:
    with pytest.raises(ValueError, match="free_axis must be one of"):
        IKOptions(free_axis="w")
    with pytest.raises(ValueError, match="not both"):
        IKOptions(free_axis="z", position_only=True)
    with pytest.raises(ValueError, match="tolerances must be positive"):
        IKOptions(position_tolerance=0.0)


def test_virtual_machine_fallback_gives_the_same_answers(ur3: ArmModel) -> None:
    compiled = IKSolver(ur3, DETERMINISTIC)
    plain = IKSolver(ur3, IKOptions(time_budget=None, compile=False))
    assert not plain.compiled
    for _, target in random_targets(ur3, 10, seed=31):
        a, b = compiled.solve(target), plain.solve(target)
        assert a.success == b.success and a.restarts == b.restarts
        np.testing.assert_allclose(a.q, b.q, atol=1e-9)


@pytest.mark.skipif(shutil.which("gcc") is None and shutil.which("cc") is None,
                    reason="no C compiler")
def test_compiled_library_is_cached(
    ur3: ArmModel, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("BT_MANIP_IK_CACHE", str(tmp_path))
    monkeypatch.delenv("BT_MANIP_NO_COMPILE", raising=False)
    function = attempt_function(ur3, "position", 3)
    runner = load_runner(function)
    assert isinstance(runner, CompiledRunner)
    libraries = list(tmp_path.glob("*.so"))
    assert len(libraries) == 1
    stamp = libraries[0].stat().st_mtime_ns
    again = load_runner(function)
    assert isinstance(again, CompiledRunner)
    assert libraries[0].stat().st_mtime_ns == stamp
    assert list(tmp_path.glob("*.so")) == libraries
