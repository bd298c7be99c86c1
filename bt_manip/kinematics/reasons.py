"""Texts that say why an IK target failed, phrased so a user can act on them.

Each starts with a fixed cause (``beyond reach``, ``joint limits``, ``not converged in the
budget``) that behaviours and tests can match, followed by the figures behind it.
"""

from __future__ import annotations

import math

import numpy as np

from bt_manip.kinematics.arm_model import ArmModel

BEYOND_REACH = "beyond reach"
JOINT_LIMITS = "joint limits"
NOT_CONVERGED = "not converged in the budget"
SOLVER_KNOBS = (
    "try another seed (IKOptions.seed), a larger budget (IKOptions.max_restarts, time_budget) "
    "or a partial target (IKOptions.free_axis: the rotation about that tool axis left free; "
    "position_only)"
)
"""The end of a :func:`not_converged` reason: the solver's options that could change the
outcome (a node that calls the solver replaces it with its own ports)."""


def beyond_reach(distance: float, reach: float) -> str:
    """The target is farther from the shoulder than the arm can stretch."""
    return (
        f"{BEYOND_REACH}: target {distance:.2f} m from the shoulder, reach {reach:.2f} m; "
        "move the base closer or pick a nearer target"
    )


def wrap_into_limits(arm: ArmModel, q: np.ndarray) -> np.ndarray:
    """Shift revolute joints by whole turns towards their ranges (same pose)."""
    out = np.array(q, dtype=float)
    for i, joint in enumerate(arm.chain):
        if joint.kind != "revolute":
            continue
        turn = 2.0 * math.pi
        while out[i] > joint.upper and out[i] - turn >= joint.lower - 1e-12:
            out[i] -= turn
        while out[i] < joint.lower and out[i] + turn <= joint.upper + 1e-12:
            out[i] += turn
        if out[i] > joint.upper or out[i] < joint.lower:
            # Not inside either way: report the value closest to the range.
            centre = 0.5 * (joint.lower + joint.upper)
            out[i] = centre + math.remainder(out[i] - centre, turn)
    return out


def joint_limits(arm: ArmModel, q_free: np.ndarray) -> str | None:
    """No solution within the limits was found, but ``q_free`` (outside them) reaches the pose.

    Returns None when ``q_free`` turns out to fit the limits after all.
    """
    q = wrap_into_limits(arm, q_free)
    outside = []
    for value, joint in zip(q, arm.chain, strict=True):
        if value > joint.upper + 1e-9 or value < joint.lower - 1e-9:
            unit = "rad" if joint.kind == "revolute" else "m"
            outside.append(
                f"{joint.name} at {value:.2f} {unit} (limits {joint.lower:.2f} .. "
                f"{joint.upper:.2f})"
            )
    if not outside:
        return None
    return (
        f"{JOINT_LIMITS}: the solutions found need " + ", ".join(outside)
        + "; approach from another direction or move the base"
    )


def not_converged(
    position_error: float,
    rotation_error: float,
    restarts: int,
    iterations: int,
    elapsed: float,
    time_budget: float | None,
) -> str:
    """No attempt reached the tolerance; give the best error, what was spent, and the
    :class:`~bt_manip.kinematics.ik.IKOptions` that could change the outcome."""
    spent = (
        f"time budget of {time_budget * 1e3:.1f} ms spent"
        if time_budget is not None
        else f"{restarts} restarts"
    )
    return (
        f"{NOT_CONVERGED} ({spent}, {iterations} iterations, {elapsed * 1e3:.1f} ms): best "
        f"error {position_error * 1e3:.2f} mm / {math.degrees(rotation_error):.2f} deg; the "
        f"pose may be at the edge of the workspace or blocked by joint limits: {SOLVER_KNOBS}"
    )
