"""The odometry motion model of a differential-drive base (AMCL's "diff" model).

Between two odometry poses the base is taken to have turned by ``rot1`` towards where it went,
driven ``trans`` in a straight line, and turned by ``rot2`` to its new heading. Each particle
moves by its own noisy copy of that motion (Thrun, Burgard and Fox, *Probabilistic Robotics*,
table 5.6), with the variances

- ``rot1``: ``alpha1 * rot1^2 + alpha2 * trans^2``
- ``trans``: ``alpha3 * trans^2 + alpha4 * (rot1^2 + rot2^2)``
- ``rot2``: ``alpha1 * rot2^2 + alpha2 * trans^2``

:func:`sample_motion_planar` is the "planar" model, the default of bt-manip's filter: the move
taken apart into its forward, sideways and turning parts in the base's frame, each noisy. A
skid-steer base turning on the spot slides sideways a few centimetres about a pivot its wheels
do not measure well; the diff model reads that slide as a quarter turn towards it and back, and
its noise, proportional to those turns, scatters the particles over a metre.

As in AMCL, the turns that enter the variances are measured modulo a half turn, so that
driving backwards does not count as two half turns, and ``rot1`` is taken as 0 for a move
shorter than a centimetre (the direction of a tiny move is noise).
"""

from __future__ import annotations

import math

import numpy as np

_SHORT_MOVE = 0.01
"""Moves (m) shorter than this have no meaningful direction."""


def wrap(a: np.ndarray | float) -> np.ndarray | float:
    """Angle(s) wrapped into [-pi, pi)."""
    return (np.asarray(a) + math.pi) % (2.0 * math.pi) - math.pi


def _wrap_f(a: float) -> float:
    return (a + math.pi) % (2.0 * math.pi) - math.pi


def odometry_delta(
    old: tuple[float, float, float], new: tuple[float, float, float]
) -> tuple[float, float, float]:
    """``(rot1, trans, rot2)`` of the move from ``old`` to ``new`` (x, y, yaw)."""
    dx, dy = new[0] - old[0], new[1] - old[1]
    trans = math.hypot(dx, dy)
    rot1 = 0.0 if trans < _SHORT_MOVE else _wrap_f(math.atan2(dy, dx) - old[2])
    rot2 = _wrap_f(new[2] - old[2] - rot1)
    return rot1, trans, rot2


def _turn_for_noise(rot: float) -> float:
    """The size of a turn, forward or backward (the smaller of ``|rot|`` and ``|rot - pi|``)."""
    return min(abs(_wrap_f(rot)), abs(_wrap_f(rot - math.pi)))


def sample_motion(
    poses: np.ndarray,
    old: tuple[float, float, float],
    new: tuple[float, float, float],
    alphas: tuple[float, ...],
    rng: np.random.Generator,
) -> np.ndarray:
    """``poses`` (n, 3) moved by a noisy copy each of the odometry move ``old`` -> ``new``
    (AMCL's diff model); ``alphas``: ``(alpha1, alpha2, alpha3, alpha4)``, any further value
    unused.

    Returns a new array; yaw wrapped into [-pi, pi).
    """
    a1, a2, a3, a4 = alphas[:4]
    rot1, trans, rot2 = odometry_delta(old, new)
    r1 = _turn_for_noise(rot1)
    r2 = _turn_for_noise(rot2)
    n = poses.shape[0]
    noise = rng.standard_normal((n, 3))
    sd_rot1 = math.sqrt(a1 * r1 * r1 + a2 * trans * trans)
    sd_trans = math.sqrt(a3 * trans * trans + a4 * (r1 * r1 + r2 * r2))
    sd_rot2 = math.sqrt(a1 * r2 * r2 + a2 * trans * trans)
    rot1_hat = rot1 - sd_rot1 * noise[:, 0]
    trans_hat = trans - sd_trans * noise[:, 1]
    rot2_hat = rot2 - sd_rot2 * noise[:, 2]
    heading = poses[:, 2] + rot1_hat
    out = np.empty_like(poses)
    out[:, 0] = poses[:, 0] + trans_hat * np.cos(heading)
    out[:, 1] = poses[:, 1] + trans_hat * np.sin(heading)
    out[:, 2] = wrap(heading + rot2_hat)
    return out


def sample_motion_planar(
    poses: np.ndarray,
    old: tuple[float, float, float],
    new: tuple[float, float, float],
    alphas: tuple[float, ...],
    rng: np.random.Generator,
) -> np.ndarray:
    """``poses`` (n, 3) moved by a noisy copy each of the odometry move ``old`` -> ``new``,
    the move taken as a translation (forward ``dx``, sideways ``dy``) and a turn ``dyaw`` in
    the base's frame at ``old``, each part with its own noise (the "planar" model):

    - forward: variance ``alpha3 * trans^2 + alpha4 * dyaw^2``;
    - sideways: variance ``alpha3 * dy^2 + alpha5 * dyaw^2`` (a base that turns also slips
      across, by more than its odometry says);
    - turn: variance ``alpha1 * dyaw^2 + alpha2 * trans^2``.

    Unlike the diff model, a short move to the side (a skid-steer sliding about its pivot as
    it turns on the spot) is not read as a large turn towards it followed by a turn back,
    whose noise would scatter the particles over metres.
    """
    a1, a2, a3, a4 = alphas[:4]
    a5 = alphas[4] if len(alphas) > 4 else 0.0
    c, s = math.cos(old[2]), math.sin(old[2])
    ddx, ddy = new[0] - old[0], new[1] - old[1]
    dx, dy = c * ddx + s * ddy, -s * ddx + c * ddy
    dyaw = _wrap_f(new[2] - old[2])
    trans2 = dx * dx + dy * dy
    turn2 = dyaw * dyaw
    n = poses.shape[0]
    noise = rng.standard_normal((n, 3))
    fx = dx + math.sqrt(a3 * trans2 + a4 * turn2) * noise[:, 0]
    fy = dy + math.sqrt(a3 * dy * dy + a5 * turn2) * noise[:, 1]
    fyaw = dyaw + math.sqrt(a1 * turn2 + a2 * trans2) * noise[:, 2]
    cp, sp = np.cos(poses[:, 2]), np.sin(poses[:, 2])
    out = np.empty_like(poses)
    out[:, 0] = poses[:, 0] + cp * fx - sp * fy
    out[:, 1] = poses[:, 1] + sp * fx + cp * fy
    out[:, 2] = wrap(poses[:, 2] + fyaw)
    return out
