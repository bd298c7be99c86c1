"""Forward kinematics of an :class:`~bt_manip.kinematics.arm_model.ArmModel` as a CasADi graph.

The PyPI ``pin`` wheel ships without ``pinocchio.casadi``, so the graph is built here from the
chain that the arm model reads out of Pinocchio: each joint's fixed placement, its kind and its
axis, then the tip placement. The same recursion as Pinocchio's forward pass,

    T_i = T_{i-1} * placement_i * motion_i(q_i),   tip = T_n * tip_placement,

is written with CasADi ``SX`` symbols, so the result can be differentiated, embedded in solvers
or turned into C code. The geometric Jacobian comes from the joint frames of the same pass
(``z_i x (p - o_i)`` over ``z_i`` for a revolute joint, ``z_i`` over zero for a prismatic one).
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from bt_manip.kinematics.arm_model import ArmModel


@dataclass
class FKGraph:
    """Symbolic kinematics of the tip: rotation ``R`` (3x3), position ``p`` (3), Jacobian ``J``.

    ``J`` is 6 x nq, linear rows first, all in the base frame.
    """

    q: ca.SX
    R: ca.SX
    p: ca.SX
    J: ca.SX


def _skew(u: np.ndarray) -> np.ndarray:
    return np.array([[0.0, -u[2], u[1]], [u[2], 0.0, -u[0]], [-u[1], u[0], 0.0]])


def _axis_rotation(axis: np.ndarray, angle: ca.SX) -> ca.SX:
    """Rotation of ``angle`` about a constant unit ``axis`` (Rodrigues' formula).

    ``R = I + sin(angle) K + (1 - cos(angle)) K^2`` with ``K`` the cross-product matrix of the
    axis. Entries whose constant factors are exactly 0 or +-1 (all of them for an axis-aligned
    joint) are written without the redundant terms, leaving the usual three-entry rotation.
    """
    c, s = ca.cos(angle), ca.sin(angle)
    k = _skew(axis)
    k2 = k @ k
    rot = ca.SX(3, 3)
    for r in range(3):
        for col in range(3):
            diagonal = r == col
            kk, kk2 = k[r, col], k2[r, col]
            if kk == 0.0 and kk2 == 0.0:
                entry = ca.SX(1.0 if diagonal else 0.0)
            elif diagonal and kk == 0.0 and kk2 == -1.0:
                entry = c  # 1 + (1 - c) * (-1)
            elif not diagonal and kk2 == 0.0 and kk in (1.0, -1.0):
                entry = s if kk == 1.0 else -s
            else:
                entry = (1.0 if diagonal else 0.0) + s * kk + (1.0 - c) * kk2
            rot[r, col] = entry
    return rot


def fk_graph(arm: ArmModel, q: ca.SX | None = None) -> FKGraph:
    """Build the symbolic forward kinematics and geometric Jacobian of ``arm``."""
    if q is None:
        q = ca.SX.sym("q", arm.nq)
    rot: ca.SX = ca.SX.eye(3)
    pos: ca.SX = ca.SX.zeros(3)
    axes: list[ca.SX] = []
    origins: list[ca.SX] = []
    for i, joint in enumerate(arm.chain):
        # Fixed placement of the joint frame in the previous one.
        pos = pos + rot @ ca.DM(joint.translation)
        rot = rot @ ca.DM(joint.rotation)
        axis_world = rot @ ca.DM(joint.axis)
        axes.append(axis_world)
        origins.append(pos)
        if joint.kind == "revolute":
            rot = rot @ _axis_rotation(joint.axis, q[i])
        else:
            pos = pos + axis_world * q[i]
    tip_p = pos + rot @ ca.DM(arm.tip_translation)
    tip_R = rot @ ca.DM(arm.tip_rotation)
    columns = []
    for joint, z, o in zip(arm.chain, axes, origins, strict=True):
        if joint.kind == "revolute":
            columns.append(ca.vertcat(ca.cross(z, tip_p - o), z))
        else:
            columns.append(ca.vertcat(z, ca.SX.zeros(3)))
    jac = ca.horzcat(*columns)
    return FKGraph(q=q, R=tip_R, p=tip_p, J=jac)


def fk_function(arm: ArmModel) -> ca.Function:
    """CasADi function ``q -> (T 4x4, J 6 x nq)`` of the tip in the base frame."""
    g = fk_graph(arm)
    T = ca.vertcat(ca.horzcat(g.R, g.p), ca.DM([[0.0, 0.0, 0.0, 1.0]]))
    return ca.Function("fk", [g.q], [T, g.J], ["q"], ["T", "J"])
