"""The IK iteration as a CasADi graph: one damped Gauss-Newton (Levenberg-Marquardt) step.

Each step evaluates the symbolic forward kinematics of :mod:`bt_manip.kinematics.casadi_fk`,
the task error ``e`` and the task Jacobian ``J``, then takes

    dq = (J^T J + lambda I)^-1 J^T (e - J z) + z,   z = -w (q - q_ref)

with ``lambda = damping * |e|^2 + bias`` (the error-dependent damping of Sugihara's
Levenberg-Marquardt IK): a damped least-squares step towards the target plus a posture pull
``z`` towards ``q_ref`` that only acts (approximately) in the task's null space; ``w = 0``
disables it. The step is scaled so
that no joint moves more than ``max_step``, then put back inside the limits: a revolute joint
that overshoots a limit is turned by a full turn when that lands inside its range (the same
pose), and clamped otherwise. Once the error is within tolerance (and, with a posture pull,
the null-space motion has settled) the iterate freezes, so ``iterations`` counts the steps
actually needed.

``K`` such steps are folded into one CasADi function so one call runs a whole attempt; the
linear solve is an unrolled Cholesky factorisation of the small nq x nq matrix, which keeps the
graph a plain ``SX`` expression that CasADi can evaluate in its virtual machine or emit as C.

Task modes:

- ``"pose"``: position and orientation; the rotation error is ``log(R_target R^T)`` (rotation
  vector in the base frame).
- ``"axis"``: position, plus one tool axis (x, y or z) aligned with the same axis of the target;
  rotation about that axis is free. The rotation error is the rotation vector of the shortest
  turn between the two axes, and the angular rows of the Jacobian are projected off the tool
  axis so the solver does not fight a freedom the task leaves open.
- ``"position"``: position only.

Inputs of the folded function (:func:`attempt_function`): ``q0`` (nq), ``target`` (12:
rotation column-major then position), ``q_ref`` (nq), ``lower`` (nq), ``upper`` (nq),
``params`` (6: posture weight, position tolerance, rotation tolerance, damping, bias,
max_step). Outputs: ``q`` (nq), ``err``
(6: position error, rotation error in the base frame; the rotation part is zero in
``"position"`` mode), ``status`` (2: iterations taken, 1 if within tolerance else 0).
"""

from __future__ import annotations

import math

import casadi as ca

from bt_manip.kinematics.arm_model import ArmModel
from bt_manip.kinematics.casadi_fk import fk_graph

MODES = ("pose", "axis", "position")
AXES = {"x": 0, "y": 1, "z": 2}
N_PARAMS = 6
POSTURE_SETTLED = 1e-4
"""With a posture pull, an attempt stops once on target and no joint steps more than this."""


def _pick(conditions: list[ca.SX], values: list[ca.SX]) -> ca.SX:
    """``values[i]`` for the first true ``conditions[i]``, else the last value."""
    out = values[-1]
    for cond, value in zip(reversed(conditions), reversed(values[:-1]), strict=True):
        out = ca.if_else(cond, value, out)
    return out


def _rotation_vector(m: ca.SX) -> ca.SX:
    """Rotation vector (axis times angle, angle in [0, pi]) of a rotation matrix ``m``.

    Up to 90 degrees the axis comes from the skew part, ``w = sin(theta) a``. Beyond, where
    ``w`` vanishes towards 180 degrees, it comes from the symmetric part,
    ``(m + m^T) / 2 - cos(theta) I = (1 - cos(theta)) a a^T``, with the sign taken from ``w``.
    No branch divides by zero, so the graph never produces NaN.
    """
    w = 0.5 * ca.vertcat(m[2, 1] - m[1, 2], m[0, 2] - m[2, 0], m[1, 0] - m[0, 1])
    s = ca.sqrt(ca.dot(w, w))
    c = 0.5 * (m[0, 0] + m[1, 1] + m[2, 2] - 1.0)
    theta = ca.atan2(s, c)
    # theta / sin(theta); its series 1 + theta^2 / 6 near zero.
    factor = ca.if_else(s > 1e-7, theta / ca.fmax(s, 1e-7), 1.0 + theta * theta / 6.0)
    small = factor * w
    outer = (0.5 * (m + m.T) - c * ca.SX.eye(3)) / ca.fmax(1.0 - c, 1.0)
    d0, d1, d2 = outer[0, 0], outer[1, 1], outer[2, 2]
    first = ca.logic_and(d0 >= d1, d0 >= d2)
    column = _pick([first, d1 >= d2], [outer[:, 0], outer[:, 1], outer[:, 2]])
    diag = _pick([first, d1 >= d2], [d0, d1, d2])
    axis = column / ca.sqrt(ca.fmax(diag, 1e-30))
    axis = ca.if_else(ca.dot(axis, w) < 0.0, -axis, axis)
    return ca.if_else(c >= 0.0, small, theta * axis)


def _turn_between(a: ca.SX, b: ca.SX) -> ca.SX:
    """Rotation vector of the shortest turn taking unit vector ``a`` onto unit vector ``b``.

    When ``b`` is (nearly) opposite to ``a`` every axis perpendicular to ``a`` is shortest;
    one is picked from the coordinate axis least aligned with ``a``.
    """
    cr = ca.cross(a, b)
    s = ca.sqrt(ca.dot(cr, cr))
    c = ca.dot(a, b)
    theta = ca.atan2(s, c)
    factor = ca.if_else(s > 1e-7, theta / ca.fmax(s, 1e-7), 1.0 + theta * theta / 6.0)
    ax, ay, az = ca.fabs(a[0]), ca.fabs(a[1]), ca.fabs(a[2])
    basis = _pick(
        [ca.logic_and(ax <= ay, ax <= az), ay <= az],
        [ca.SX([1.0, 0.0, 0.0]), ca.SX([0.0, 1.0, 0.0]), ca.SX([0.0, 0.0, 1.0])],
    )
    perp = ca.cross(a, basis)
    perp = perp / ca.fmax(ca.sqrt(ca.dot(perp, perp)), 1e-30)
    opposite = ca.logic_and(c < 0.0, s < 1e-6)
    return ca.if_else(opposite, theta * perp, factor * cr)


def _cholesky_solve(a: ca.SX, b: ca.SX) -> ca.SX:
    """Solve ``a x = b`` for a symmetric positive definite ``a``, fully unrolled."""
    n = a.shape[0]
    low = [[ca.SX(0.0)] * n for _ in range(n)]
    for j in range(n):
        acc = a[j, j]
        for k in range(j):
            acc = acc - low[j][k] * low[j][k]
        low[j][j] = ca.sqrt(acc)
        inv = 1.0 / low[j][j]
        for i in range(j + 1, n):
            acc = a[i, j]
            for k in range(j):
                acc = acc - low[i][k] * low[j][k]
            low[i][j] = acc * inv
    y = [ca.SX(0.0)] * n
    for i in range(n):
        acc = b[i]
        for k in range(i):
            acc = acc - low[i][k] * y[k]
        y[i] = acc / low[i][i]
    x = [ca.SX(0.0)] * n
    for i in reversed(range(n)):
        acc = y[i]
        for k in range(i + 1, n):
            acc = acc - low[k][i] * x[k]
        x[i] = acc / low[i][i]
    return ca.vertcat(*x)


def _task(arm: ArmModel, q: ca.SX, target: ca.SX, mode: str, axis: int) -> tuple[ca.SX, ca.SX]:
    """Task error ``e`` (6: position, rotation) and task Jacobian (6 x nq) at ``q``."""
    g = fk_graph(arm, q)
    r_t = ca.reshape(target[:9], 3, 3)
    p_t = target[9:12]
    e_p = p_t - g.p
    jv, jw = g.J[:3, :], g.J[3:, :]
    if mode == "pose":
        e_r = _rotation_vector(r_t @ g.R.T)
        jr = jw
    elif mode == "axis":
        a = g.R[:, axis]
        e_r = _turn_between(a, r_t[:, axis])
        jr = jw - a @ (a.T @ jw)
    else:
        e_r = ca.SX.zeros(3)
        jr = ca.SX.zeros(3, arm.nq)
    return ca.vertcat(e_p, e_r), ca.vertcat(jv, jr)


def _limit(arm: ArmModel, q: ca.SX, lower: ca.SX, upper: ca.SX) -> ca.SX:
    """Bring ``q`` inside ``[lower, upper]``: a full turn for revolute joints when it fits."""
    out = []
    for i, joint in enumerate(arm.chain):
        qi, lo, hi = q[i], lower[i], upper[i]
        if joint.kind == "revolute":
            down, up = qi - 2.0 * math.pi, qi + 2.0 * math.pi
            over = ca.if_else(down >= lo, down, hi)
            under = ca.if_else(up <= hi, up, lo)
            qi = ca.if_else(qi > hi, over, ca.if_else(qi < lo, under, qi))
        else:
            qi = ca.fmin(ca.fmax(qi, lo), hi)
        out.append(qi)
    return ca.vertcat(*out)


def step_function(arm: ArmModel, mode: str, axis: str = "z") -> ca.Function:
    """One LM step: ``(state, target, q_ref, lower, upper, params) -> state``.

    ``state`` is ``[q; iterations; done; q_hit; hit]``; ``done`` becomes 1 when the error at
    ``q`` is within tolerance (and the posture pull has settled), and ``q`` then stays put.
    ``q_hit`` is the latest iterate found within tolerance (``hit`` = 1 once there is one), so a
    posture pull still moving when the steps run out keeps a valid answer.
    """
    if mode not in MODES:
        raise ValueError(f"unknown IK mode {mode!r}; expected one of {MODES}")
    n = arm.nq
    state = ca.SX.sym("state", 2 * n + 3)
    target = ca.SX.sym("target", 12)
    q_ref = ca.SX.sym("q_ref", n)
    lower = ca.SX.sym("lower", n)
    upper = ca.SX.sym("upper", n)
    params = ca.SX.sym("params", N_PARAMS)
    w_post, tol_p, tol_r, damping, bias, max_step = (params[i] for i in range(N_PARAMS))
    q, k, q_hit, hit = state[:n], state[n], state[n + 2 : 2 * n + 2], state[2 * n + 2]
    e, jac = _task(arm, q, target, mode, AXES[axis])
    on_target = ca.logic_and(ca.mmax(ca.fabs(e[:3])) <= tol_p, ca.mmax(ca.fabs(e[3:])) <= tol_r)
    lam = damping * ca.dot(e, e) + bias
    jtj = jac.T @ jac
    a = jtj + lam * ca.SX.eye(n)
    z = -w_post * (q - q_ref)
    dq = _cholesky_solve(a, jac.T @ (e - jac @ z)) + z
    largest = ca.mmax(ca.fabs(dq))
    scale = ca.fmin(1.0, max_step / ca.fmax(largest, 1e-300))
    # With a posture pull, go on moving in the null space until the steps become small.
    settled = ca.logic_or(w_post <= 0.0, largest <= POSTURE_SETTLED)
    converged = ca.logic_and(on_target, settled)
    q_next = _limit(arm, q + scale * dq, lower, upper)
    q_next = ca.if_else(converged, q, q_next)
    k_next = k + ca.if_else(converged, 0.0, 1.0)
    return ca.Function(
        f"step_{mode}",
        [state, target, q_ref, lower, upper, params],
        [
            ca.vertcat(
                q_next,
                k_next,
                converged,
                ca.if_else(on_target, q, q_hit),
                ca.if_else(on_target, 1.0, hit),
            )
        ],
    )


def error_function(arm: ArmModel, mode: str, axis: str = "z") -> ca.Function:
    """Task error at ``q``: ``(q, target) -> err`` (6)."""
    q = ca.SX.sym("q", arm.nq)
    target = ca.SX.sym("target", 12)
    e, _ = _task(arm, q, target, mode, AXES[axis])
    return ca.Function(f"error_{mode}", [q, target], [e])


def attempt_function(arm: ArmModel, mode: str, iterations: int, axis: str = "z") -> ca.Function:
    """``iterations`` LM steps folded into one function, plus the error at the final ``q``.

    ``(q0, target, q_ref, lower, upper, params) -> (q, err, status)``.
    """
    n = arm.nq
    step = step_function(arm, mode, axis)
    err = error_function(arm, mode, axis)
    # Skip the work once converged: a short-circuit conditional, so the generated C evaluates
    # one branch only and an attempt costs as many steps as it needs.
    state = ca.MX.sym("state", 2 * n + 3)
    args = [ca.MX.sym(name, size) for name, size in
            (("target", 12), ("q_ref", n), ("lower", n), ("upper", n), ("params", N_PARAMS))]
    guarded = ca.Function(
        f"guarded_{mode}",
        [state, *args],
        [ca.if_else(state[n + 1], state, step(state, *args), True)],
    )
    folded = guarded.fold(iterations)
    q0 = ca.MX.sym("q0", n)
    target, q_ref, lower, upper, params = (ca.MX.sym(a.name(), a.numel()) for a in args)

    def rep(x: ca.MX) -> ca.MX:
        return ca.repmat(x, 1, iterations)

    final = folded(
        ca.vertcat(q0, 0.0, 0.0, q0, 0.0),
        rep(target), rep(q_ref), rep(lower), rep(upper), rep(params),
    )
    q = ca.if_else(final[2 * n + 2], final[n + 2 : 2 * n + 2], final[:n])
    e = err(q, target)
    ok = ca.logic_and(
        ca.mmax(ca.fabs(e[:3])) <= params[1], ca.mmax(ca.fabs(e[3:])) <= params[2]
    )
    return ca.Function(
        f"ik_{mode}_{axis}_{n}",
        [q0, target, q_ref, lower, upper, params],
        [q, e, ca.vertcat(final[n], ok)],
        ["q0", "target", "q_ref", "lower", "upper", "params"],
        ["q", "err", "status"],
    )
