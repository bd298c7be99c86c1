"""Inverse kinematics of an :class:`~bt_manip.kinematics.arm_model.ArmModel` with CasADi.

:class:`IKSolver` finds joint values within the limits that put the tip on a target pose (or
on a partial target: position only, or orientation free about one tool axis).

How a solve runs:

1. The target is checked (finite 4x4 pose, orthonormal rotation) and compared with the arm's
   reach: a target farther from the shoulder than the arm can stretch fails at once with the
   reason ``beyond reach: target 2.00 m from the shoulder, reach 0.59 m``.
2. An attempt is up to ``iterations_per_attempt`` damped Gauss-Newton steps (see
   :mod:`bt_manip.kinematics.solver_graph`), all in one call of CasADi-generated C code
   (:mod:`bt_manip.kinematics.compiled`). The first attempt starts from the seed (the middle of
   the limits when none is given).
3. While an attempt fails, the next one starts from a random configuration within the limits,
   up to ``max_restarts`` times or until ``time_budget`` is spent.
4. If all attempts fail, a diagnosis names the cause: the same solve without limits succeeds
   (``joint limits: ...`` naming the joints that would have to leave their range), or else
   ``not converged in the budget: ...`` with the best error reached.

Success means every component of the position error is within ``position_tolerance`` and every
component of the rotation error (rotation vector of ``R_target R^T``, base frame) within
``rotation_tolerance``; the returned ``q`` is always within the joint limits.

Determinism: the random restarts come from ``numpy.random.default_rng(options.seed)``, created
afresh for each solve, so the same seed and target give the same answer bit for bit, as long
as the time budget is not what ended the search (a budget is wall-clock time, so how many
restarts fit into it depends on the machine and its load). ``time_budget=None`` makes every
solve deterministic.
"""

from __future__ import annotations

import itertools
import math
import time
from dataclasses import dataclass, field

import casadi as ca
import numpy as np

from bt_manip.kinematics.arm_model import ArmModel
from bt_manip.kinematics.compiled import FunctionRunner, VirtualMachineRunner, load_runner
from bt_manip.kinematics.reasons import beyond_reach, joint_limits, not_converged
from bt_manip.kinematics.solver_graph import AXES, attempt_function


@dataclass(frozen=True)
class IKOptions:
    """Settings of :class:`IKSolver`.

    Attributes:
        position_tolerance: largest error allowed on each position axis (m).
        rotation_tolerance: largest error allowed on each rotation axis (rad).
        time_budget: wall-clock seconds for one solve; None for no limit (fully
            deterministic). Checked between attempts, so a solve may overrun it by one
            attempt, plus the diagnosis (at most 8 attempts) when it fails.
        max_restarts: random restarts after the attempt from the seed (with the default
            budget, the time runs out first: an attempt takes tens of microseconds).
        iterations_per_attempt: damped Gauss-Newton steps in one attempt.
        posture_weight: pull towards the seed in the task's null space, as the fraction of
            the distance removed per step, in [0, 1); 0 disables it, 0.1 to 0.5 is typical.
            On a redundant arm this keeps the solution nearer the seed (attempts then run
            until the null-space motion settles, so they take more steps).
        position_only: ignore the target orientation.
        free_axis: ``"x"``, ``"y"`` or ``"z"``: align that tool axis with the same axis of the
            target and leave the rotation about it free (a top-down grasp with free yaw is
            ``free_axis="z"`` with a target whose z axis points down).
        seed: seed of the random restarts.
        damping, bias, max_step: step tuning (damping ``lambda = damping |e|^2 + bias``,
            largest joint change per step in rad or m).
        diagnose: on failure, run the unconstrained check that tells joint limits apart.
        compile: build the solver as C code (falls back to CasADi's VM when impossible).
    """

    position_tolerance: float = 1e-5
    rotation_tolerance: float = 1e-5
    time_budget: float | None = 0.01
    max_restarts: int = 1000
    iterations_per_attempt: int = 40
    posture_weight: float = 0.0
    position_only: bool = False
    free_axis: str | None = None
    seed: int = 0
    damping: float = 0.1
    bias: float = 1e-6
    max_step: float = 0.5
    diagnose: bool = True
    compile: bool = True

    def __post_init__(self) -> None:
        problems = []
        if not self.position_tolerance > 0 or not self.rotation_tolerance > 0:
            problems.append("tolerances must be positive")
        if self.time_budget is not None and not self.time_budget > 0:
            problems.append("time_budget must be positive or None")
        if self.max_restarts < 0:
            problems.append("max_restarts must be >= 0")
        if self.iterations_per_attempt < 1:
            problems.append("iterations_per_attempt must be >= 1")
        if self.posture_weight < 0 or self.posture_weight >= 1:
            problems.append("posture_weight must be in [0, 1)")
        if self.free_axis is not None and self.free_axis not in AXES:
            problems.append(f"free_axis must be one of {sorted(AXES)} or None")
        if self.free_axis is not None and self.position_only:
            problems.append("choose position_only or free_axis, not both")
        if problems:
            raise ValueError("invalid IKOptions: " + "; ".join(problems))

    @property
    def mode(self) -> str:
        """The task mode of :mod:`bt_manip.kinematics.solver_graph`."""
        if self.position_only:
            return "position"
        return "axis" if self.free_axis is not None else "pose"


@dataclass
class IKResult:
    """Outcome of :meth:`IKSolver.solve`.

    ``q`` is the solution on success and the best configuration found otherwise (always within
    the limits). ``position_error`` (m) and ``rotation_error`` (rad) are the norms of the
    remaining errors at ``q`` (NaN when the target was rejected before solving), ``error``
    the six components (position, rotation vector; base frame). ``iterations`` counts solver
    steps over all attempts, ``restarts`` the attempts after the first. ``reason`` is None on
    success and says why otherwise (see :mod:`bt_manip.kinematics.reasons`).
    """

    success: bool
    q: np.ndarray
    position_error: float
    rotation_error: float
    iterations: int
    restarts: int
    time_s: float
    reason: str | None = None
    error: np.ndarray = field(default_factory=lambda: np.zeros(6))


class IKSolver:
    """Solves the inverse kinematics of one arm (see the module docstring).

    Building a solver generates (or loads from the cache) the compiled attempt function for
    the options' task mode; reuse one solver for many targets. A solver holds preallocated
    buffers, so one instance must not be used from several threads at once.
    """

    def __init__(self, arm: ArmModel, options: IKOptions | None = None) -> None:
        self.arm = arm
        self.options = options or IKOptions()
        o = self.options
        axis = o.free_axis or "z"
        key = (arm._chain_key(), o.mode, o.iterations_per_attempt, axis)
        function = _attempt_function(arm, key)
        if o.compile:
            self._runner: FunctionRunner = load_runner(function, key)
        else:
            self._runner = VirtualMachineRunner(function)
        self._params = np.array(
            [o.posture_weight, o.position_tolerance, o.rotation_tolerance, o.damping, o.bias,
             o.max_step]
        )
        self._lower = arm.lower.copy()
        self._upper = arm.upper.copy()
        _, _, _, lower, upper, params = self._runner.inputs
        lower[:] = self._lower
        upper[:] = self._upper
        params[:] = self._params
        self._free_lower = np.full(arm.nq, -np.inf)
        self._free_upper = np.full(arm.nq, np.inf)
        self._shoulder = arm.shoulder()
        sx, sy, sz = self._shoulder.tolist()
        self._shoulder_xyz = (float(sx), float(sy), float(sz))
        # A small margin over the numerically maximised reach (see ArmModel.reach).
        self._reach = arm.reach()
        self._reach_limit = self._reach * (1.0 + 1e-3) + o.position_tolerance

    @property
    def compiled(self) -> bool:
        """True when attempts run as compiled C code."""
        return self._runner.compiled

    def solve(self, target: np.ndarray, q_seed: np.ndarray | None = None) -> IKResult:
        """Joint values that put the tip on ``target`` (4x4 pose in the base frame).

        ``q_seed`` is the first starting point and, with a posture weight, the posture to
        stay near; the middle of the limits when None. Never raises for a bad target or
        seed: the result then fails with an ``invalid ...`` reason.
        """
        start = time.perf_counter()
        o = self.options
        arm = self.arm
        seed, problem = self._load(target, q_seed)
        if problem is not None:
            return self._failure(seed, problem, start)
        r = self._runner
        q0 = r.inputs[0]
        out_q, out_err, out_status = r.outputs
        rng: np.random.Generator | None = None
        iterations = 0
        best_q, best_err, best_score = seed.copy(), None, math.inf
        deadline = None if o.time_budget is None else start + o.time_budget
        budget_hit = False
        attempt = 0
        for attempt in range(o.max_restarts + 1):
            r.run()
            iterations += int(out_status[0])
            if out_status[1] > 0.5:
                return self._result(True, out_q.copy(), out_err.copy(), iterations, attempt, start)
            score = self._score(out_err)
            if score < best_score:
                best_q, best_err, best_score = out_q.copy(), out_err.copy(), score
            if deadline is not None and time.perf_counter() > deadline:
                budget_hit = True
                break
            if rng is None:
                rng = np.random.default_rng(o.seed)
            q0[:] = rng.uniform(arm.lower, arm.upper)

        if best_err is None:  # no attempt gave a comparable error (NaN)
            best_err = np.full(6, np.inf)
        reason = None
        if o.diagnose:
            reason = self._diagnose_limits(best_q, rng or np.random.default_rng(o.seed))
        if reason is None:
            reason = not_converged(
                _norm3(best_err[:3]),
                _norm3(best_err[3:]),
                attempt,
                iterations,
                time.perf_counter() - start,
                o.time_budget if budget_hit else None,
            )
        return self._result(False, best_q, best_err, iterations, attempt, start, reason)

    def solve_q(self, target: np.ndarray, q_seed: np.ndarray) -> np.ndarray | None:
        """The joint values ``solve(target, q_seed)`` returns when its first attempt (the one
        from the seed) succeeds, else None: the same numbers without a result record, for
        callers that solve many targets in a row and call :meth:`solve` for the reason only
        when this gives None."""
        _, problem = self._load(target, q_seed)
        if problem is not None:
            return None
        r = self._runner
        r.run()
        out_q, _, out_status = r.outputs
        return out_q.copy() if out_status[1] > 0.5 else None

    # ------------------------------------------------------------------ helpers
    def _load(self, target: np.ndarray, q_seed: np.ndarray | None) -> tuple[np.ndarray, str | None]:
        """Check ``target`` and ``q_seed`` and load the solver's inputs for the attempt from
        the seed: (the seed, clipped to the limits, and None), or (the configuration to report,
        why there is nothing to solve)."""
        arm = self.arm
        seed = arm.mid.copy() if q_seed is None else np.array(q_seed, dtype=float)
        t = np.asarray(target, dtype=float)
        rows = t.tolist() if t.shape == (4, 4) else None
        problem = self._check_target(rows, seed)
        if problem is not None or rows is None:
            usable = seed.shape == (arm.nq,) and _finite(seed)
            return (seed if usable else arm.mid), problem or ""
        np.maximum(seed, arm.lower, out=seed)  # numpy.clip(seed, lower, upper), in place
        np.minimum(seed, arm.upper, out=seed)
        # the target's values as plain floats: the same numbers numpy would hand on
        (r00, r01, r02, x), (r10, r11, r12, y), (r20, r21, r22, z) = rows[:3]
        sx, sy, sz = self._shoulder_xyz
        distance = _norm3((x - sx, y - sy, z - sz))
        if distance > self._reach_limit:
            return seed, beyond_reach(distance, self._reach)
        # (the limits and parameters stay loaded from the constructor: only the diagnosis
        # changes the limits, and it puts them back)
        q0, tgt, q_ref = self._runner.inputs[:3]
        tgt[:] = (r00, r10, r20, r01, r11, r21, r02, r12, r22, x, y, z)  # rotation column-major
        q_ref[:] = seed
        q0[:] = seed
        return seed, None

    def _score(self, err: np.ndarray) -> float:
        o = self.options
        return float(
            np.max(np.abs(err[:3])) / o.position_tolerance
            + np.max(np.abs(err[3:])) / o.rotation_tolerance
        )

    def _check_target(self, rows: list[list[float]] | None, seed: np.ndarray) -> str | None:
        """Why a target (``rows``: its 4x4 values, None when it is not 4x4) or a seed cannot be
        solved for, or None."""
        if rows is None or not all(map(math.isfinite, itertools.chain.from_iterable(rows))):
            return "invalid target: expected a finite 4x4 homogeneous pose"
        if not self.options.position_only:
            # R^T R - I must vanish and det R be positive (plain floats: nine values)
            (a, b, c, _), (d, e, f, _), (g, h, i, _) = rows[:3]
            off = max(
                abs(a * a + d * d + g * g - 1.0),
                abs(b * b + e * e + h * h - 1.0),
                abs(c * c + f * f + i * i - 1.0),
                abs(a * b + d * e + g * h),
                abs(a * c + d * f + g * i),
                abs(b * c + e * f + h * i),
            )
            det = a * (e * i - f * h) - b * (d * i - f * g) + c * (d * h - e * g)
            if off > 1e-6 or det < 0:
                return "invalid target: the rotation part is not a rotation matrix"
        if seed.shape != (self.arm.nq,) or not _finite(seed):
            return f"invalid seed: expected {self.arm.nq} finite joint values"
        return None

    def _result(
        self,
        success: bool,
        q: np.ndarray,
        err: np.ndarray,
        iterations: int,
        restarts: int,
        start: float,
        reason: str | None = None,
    ) -> IKResult:
        return IKResult(
            success=success,
            q=q,
            position_error=_norm3(err[:3]),
            rotation_error=_norm3(err[3:]),
            iterations=iterations,
            restarts=restarts,
            time_s=time.perf_counter() - start,
            reason=reason,
            error=err,
        )

    def _failure(self, q: np.ndarray, reason: str, start: float) -> IKResult:
        q = np.clip(q, self.arm.lower, self.arm.upper)
        return IKResult(
            success=False,
            q=q,
            position_error=math.nan,
            rotation_error=math.nan,
            iterations=0,
            restarts=0,
            time_s=time.perf_counter() - start,
            reason=reason,
            error=np.full(6, np.nan),
        )

    def _diagnose_limits(self, best_q: np.ndarray, rng: np.random.Generator) -> str | None:
        """Solve again without limits; a success means the limits are what blocks the pose."""
        r = self._runner
        q0, _, _, lower, upper, _ = r.inputs
        lower[:] = self._free_lower
        upper[:] = self._free_upper
        found = None
        try:
            for k in range(8):
                q0[:] = best_q if k == 0 else rng.uniform(self.arm.lower, self.arm.upper)
                r.run()
                if r.outputs[2][1] > 0.5:
                    found = r.outputs[0].copy()
                    break
        finally:
            lower[:] = self._lower
            upper[:] = self._upper
        if found is None:
            return None
        return joint_limits(self.arm, found)


_ATTEMPT_MEMO: dict[tuple[bytes, str, int, str], ca.Function] = {}
"""Attempt functions already built in this process, by (the arm's chain key, mode, steps per
attempt, free axis): every episode builds its solvers afresh, and building the CasADi graph
costs more than the rest of a solver. The graph depends on those numbers only."""
_ATTEMPT_MEMO_SIZE = 64


def _attempt_function(arm: ArmModel, key: tuple[bytes, str, int, str]) -> ca.Function:
    """:func:`attempt_function` of ``arm`` for ``key`` (see :data:`_ATTEMPT_MEMO`)."""
    function = _ATTEMPT_MEMO.get(key)
    if function is None:
        _, mode, iterations, axis = key
        function = attempt_function(arm, mode, iterations, axis)
        if len(_ATTEMPT_MEMO) >= _ATTEMPT_MEMO_SIZE:
            _ATTEMPT_MEMO.pop(next(iter(_ATTEMPT_MEMO)), None)
        _ATTEMPT_MEMO[key] = function
    return function


def _norm3(v: np.ndarray | tuple[float, float, float]) -> float:
    """Euclidean norm of a 3-vector (cheaper than numpy.linalg.norm for tiny arrays)."""
    x, y, z = float(v[0]), float(v[1]), float(v[2])
    return math.sqrt(x * x + y * y + z * z)


def _finite(a: np.ndarray) -> bool:
    """Whether every value of ``a`` is finite (``numpy.isfinite(a).all()`` for a few values,
    on plain floats)."""
    return all(map(math.isfinite, a.ravel().tolist()))
