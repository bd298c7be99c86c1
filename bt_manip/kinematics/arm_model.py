"""The kinematic chain of one arm, read from a URDF with Pinocchio.

An :class:`ArmModel` is the serial chain ``base_link -> tip_link`` of a robot description. The
URDF may describe a whole mobile manipulator (wheels, a mobile base, an arm and a gripper): every
joint outside the chain is locked at its neutral value, so the model only ever moves the arm.

Forward kinematics and the Jacobian are computed by Pinocchio and expressed in the base link's
frame. The chain is also exported as a plain list of :class:`ChainJoint` (fixed placement, joint
kind, axis) so that other modules can rebuild the same kinematics in another tool (see
:mod:`bt_manip.kinematics.casadi_fk`).

>>> arm = ArmModel.from_urdf(ur3_urdf(), base_link="base_link", tip_link="tool0")
>>> arm.nq, arm.joint_names[0]
(6, 'shoulder_pan_joint')
>>> T = arm.fk(arm.mid)          # 4x4 pose of tool0 in base_link
"""

from __future__ import annotations

import hashlib
import math
import os
import tempfile
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import cast

import numpy as np
import pinocchio as pin

from bt_manip.kinematics.compiled import cache_dir


class KinematicsError(ValueError):
    """A robot description that cannot serve as an arm (bad link names, unsupported joints)."""


@dataclass(frozen=True)
class ChainJoint:
    """One movable joint of the chain.

    ``rotation`` and ``translation`` place the joint frame in the previous joint frame (in the
    base link frame for the first joint), at joint value zero. The joint turns about (revolute)
    or slides along (prismatic) ``axis``, a unit vector in its own frame.
    """

    name: str
    kind: str  # "revolute" or "prismatic"
    axis: np.ndarray
    rotation: np.ndarray
    translation: np.ndarray
    lower: float
    upper: float


_WIDE = 1e10  # pinocchio's "no limit" is +-1.8e308; anything beyond this counts as unlimited
_REACH_MEMO: dict[bytes, float] = {}
"""Reaches already maximised in this process, by :meth:`ArmModel._chain_key`: every episode
builds its arm models afresh, and the maximisation (16 quasi-Newton runs) costs more than
the rest of the model; the value depends on the chain's numbers only."""
_REACH_MEMO_SIZE = 64


def write_configuration(out: np.ndarray, slots: Sequence[tuple[int, int]],
                        q: np.ndarray) -> np.ndarray:
    """Write one value a joint, ``q``, into Pinocchio's configuration vector ``out`` at each
    joint's slot ``(idx_q, nq)``: a continuous joint (nq 2) as the (cos, sin) of its angle.
    Returns ``out``."""
    for (idx, nq), value in zip(slots, q, strict=True):
        if nq == 1:
            out[idx] = value
        else:
            out[idx] = math.cos(value)
            out[idx + 1] = math.sin(value)
    return out


class ArmModel:
    """A serial arm: the chain ``base_link -> tip_link`` of a Pinocchio model.

    ``model`` is the whole robot; joints outside the chain stay at their neutral values.

    Attributes:
        joint_names: movable joints from the base to the tip.
        lower, upper: joint limits (rad or m). Continuous joints get ``[-pi, pi]``.
        nq: number of movable joints.
        chain: the chain as :class:`ChainJoint` records; ``tip_rotation`` and
            ``tip_translation`` place the tip link in the last joint frame.
    """

    def __init__(
        self,
        model: pin.Model,
        base_link: str,
        tip_link: str,
        chain: list[ChainJoint],
        tip_rotation: np.ndarray,
        tip_translation: np.ndarray,
        source: str = "",
    ) -> None:
        self.model = model
        self.data = model.createData()
        self.base_link = base_link
        self.tip_link = tip_link
        self.chain = chain
        self.tip_rotation = tip_rotation
        self.tip_translation = tip_translation
        self.source = source
        self.joint_names: list[str] = [j.name for j in chain]
        self.nq: int = len(chain)
        self.lower = np.array([j.lower for j in chain], dtype=float)
        self.upper = np.array([j.upper for j in chain], dtype=float)
        self.mid = 0.5 * (self.lower + self.upper)
        self._base_id = model.getFrameId(base_link, pin.FrameType.BODY)
        self._tip_id = model.getFrameId(tip_link, pin.FrameType.BODY)
        # Slots of each chain joint in Pinocchio's configuration vector; continuous joints
        # are stored as (cos, sin) there.
        self._slots: list[tuple[int, int]] = []
        self._columns: list[int] = []
        for name in self.joint_names:
            jm = model.joints[model.getJointId(name)]
            self._slots.append((jm.idx_q, jm.nq))
            self._columns.append(jm.idx_v)
        self._q_pin: np.ndarray = pin.neutral(model)
        # Joints above the base are locked, so the base placement never changes.
        pin.framesForwardKinematics(model, self.data, self._q_pin)
        self._base_inv = self.data.oMf[self._base_id].inverse()
        self._base_rot_t = self._base_inv.rotation.copy()
        self._reach: float | None = None

    # ------------------------------------------------------------------ construction
    @classmethod
    def from_urdf(
        cls,
        path: str | Path,
        base_link: str = "base_link",
        tip_link: str = "tool0",
        package_dirs: list[str] | None = None,
    ) -> ArmModel:
        """Read the chain ``base_link -> tip_link`` from a URDF file.

        Only the kinematic tree is read (no meshes), so ``package_dirs`` is accepted for
        symmetry with Pinocchio's loaders and is not needed. Raises :class:`KinematicsError`
        naming the problem when a link is missing, the tip is not below the base, or the
        chain holds a joint that is neither revolute, continuous nor prismatic.
        """
        del package_dirs  # the kinematic model needs no mesh lookup
        path = Path(path)
        if not path.is_file():
            raise KinematicsError(f"{path}: URDF file not found")
        try:
            full = pin.buildModelFromUrdf(str(path))
        except (ValueError, RuntimeError) as exc:
            raise KinematicsError(f"{path}: cannot read URDF: {exc}") from exc
        return cls.from_model(full, base_link, tip_link, source=str(path))

    @classmethod
    def from_model(
        cls, full: pin.Model, base_link: str, tip_link: str, source: str = "<model>"
    ) -> ArmModel:
        """Build the arm from an already loaded Pinocchio model (see :meth:`from_urdf`)."""
        links = [f.name for f in full.frames if f.type == pin.FrameType.BODY]
        for role, name in (("base_link", base_link), ("tip_link", tip_link)):
            if not full.existFrame(name, pin.FrameType.BODY):
                raise KinematicsError(
                    f"{source}: {role} {name!r} is not a link of the robot; links are: "
                    + ", ".join(links)
                )
        base_joint = full.frames[full.getFrameId(base_link, pin.FrameType.BODY)].parentJoint
        tip_joint = full.frames[full.getFrameId(tip_link, pin.FrameType.BODY)].parentJoint
        path: list[int] = []
        j = tip_joint
        while j != base_joint and j != 0:
            path.append(j)
            j = full.parents[j]
        if j != base_joint:
            raise KinematicsError(
                f"{source}: tip_link {tip_link!r} is not below base_link {base_link!r}"
            )
        path.reverse()
        if not path:
            raise KinematicsError(
                f"{source}: no movable joint between {base_link!r} and {tip_link!r}"
            )
        chain, tip_rot, tip_trans = _extract_chain(full, path, base_link, tip_link, source)
        return cls(full, base_link, tip_link, chain, tip_rot, tip_trans, source)

    # ------------------------------------------------------------------ kinematics
    def _to_pin(self, q: np.ndarray) -> np.ndarray:
        return write_configuration(self._q_pin, self._slots, q)

    def fk(self, q: np.ndarray) -> np.ndarray:
        """Pose of the tip link in the base link frame, as a 4x4 homogeneous matrix."""
        q = np.asarray(q, dtype=float)
        if q.shape != (self.nq,):
            raise ValueError(f"expected {self.nq} joint values, got shape {q.shape}")
        qp = self._to_pin(q)
        pin.forwardKinematics(self.model, self.data, qp)
        tip = pin.updateFramePlacement(self.model, self.data, self._tip_id)
        return cast(np.ndarray, (self._base_inv * tip).homogeneous)  # pinocchio: no stubs

    def jacobian(self, q: np.ndarray) -> np.ndarray:
        """Geometric Jacobian (6 x nq) of the tip, expressed in the base link frame.

        Rows 0-2: linear velocity of the tip origin; rows 3-5: angular velocity.
        """
        q = np.asarray(q, dtype=float)
        if q.shape != (self.nq,):
            raise ValueError(f"expected {self.nq} joint values, got shape {q.shape}")
        qp = self._to_pin(q)
        jac = _six_rows(pin.computeFrameJacobian(
            self.model, self.data, qp, self._tip_id, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
        ))
        jac = jac[:, self._columns]
        out = np.empty((6, self.nq))
        out[:3] = self._base_rot_t @ jac[:3]
        out[3:] = self._base_rot_t @ jac[3:]
        return out

    def within_limits(self, q: np.ndarray, slack: float = 0.0) -> bool:
        """True when every joint value lies in ``[lower - slack, upper + slack]``."""
        q = np.asarray(q, dtype=float)
        return bool(np.all(q >= self.lower - slack) and np.all(q <= self.upper + slack))

    def random_configuration(self, rng: np.random.Generator) -> np.ndarray:
        """A joint vector drawn uniformly within the limits."""
        return rng.uniform(self.lower, self.upper)

    def shoulder(self) -> np.ndarray:
        """Origin of the first joint in the base frame (fixed whatever the joint values)."""
        return self.chain[0].translation.copy()

    def reach_bound(self) -> float:
        """A guaranteed upper bound of the distance from :meth:`shoulder` to the tip.

        Sum of the fixed offsets along the chain (plus the longest stroke of each prismatic
        joint): by the triangle inequality no configuration puts the tip farther away. Often
        loose (offsets at right angles add up), see :meth:`reach`.
        """
        total = float(np.linalg.norm(self.tip_translation))
        for joint in self.chain[1:]:
            total += float(np.linalg.norm(joint.translation))
        for joint in self.chain:
            if joint.kind == "prismatic":
                total += max(abs(joint.lower), abs(joint.upper))
        return total

    def reach(self) -> float:
        """Largest distance from :meth:`shoulder` to the tip over the joint limits.

        Found once by maximising the distance with a bounded quasi-Newton method from a fixed
        set of starts (deterministic), and never above :meth:`reach_bound`. A numerical
        maximum: callers that reject targets with it should leave a small margin.

        The value depends on the chain's numbers only, so it is kept per chain: in this process
        and in the IK cache folder (``reach/``, next to the compiled IK code), where later
        processes find it.
        """
        if self._reach is None:
            key = self._chain_key()
            reach = _REACH_MEMO.get(key)
            if reach is None:
                reach = _stored_reach(key)
            if reach is None:
                reach = min(self._maximise_reach(), self.reach_bound())
                _store_reach(key, reach)
            if len(_REACH_MEMO) >= _REACH_MEMO_SIZE:
                _REACH_MEMO.pop(next(iter(_REACH_MEMO)))
            _REACH_MEMO[key] = reach
            self._reach = reach
        return self._reach

    def _chain_key(self) -> bytes:
        """Every number the chain's kinematics depend on (placements, axes, kinds, limits and
        the tip's placement), as bytes: two models with equal keys have equal reaches."""
        parts = [self.tip_rotation, self.tip_translation]
        for j in self.chain:
            parts += [j.rotation, j.translation, j.axis, np.array([j.lower, j.upper])]
        kinds = "".join(j.kind[0] for j in self.chain).encode()
        return kinds + b"".join(np.ascontiguousarray(p, dtype=float).tobytes() for p in parts)

    def _maximise_reach(self, starts: int = 16) -> float:
        from scipy.optimize import minimize

        s = self.shoulder()

        def cost(q: np.ndarray) -> tuple[float, np.ndarray]:
            d = self.fk(q)[:3, 3] - s
            grad = -2.0 * (self.jacobian(q)[:3].T @ d)
            return -float(d @ d), grad

        rng = np.random.default_rng(12345)
        best = 0.0
        bounds = list(zip(self.lower, self.upper, strict=True))
        for k in range(starts):
            q0 = self.mid if k == 0 else self.random_configuration(rng)
            out = minimize(cost, q0, jac=True, method="L-BFGS-B", bounds=bounds)
            best = max(best, math.sqrt(max(-float(out.fun), 0.0)))
        return best

    def __repr__(self) -> str:
        return (
            f"ArmModel({self.base_link!r} -> {self.tip_link!r}, {self.nq} joints: "
            + ", ".join(self.joint_names)
            + ")"
        )


_REACH_VERSION = b"reach-1:16-starts:rng-12345:"
"""Part of every stored reach's key: change it when the maximisation changes."""


def _reach_file(key: bytes) -> Path:
    digest = hashlib.sha256(_REACH_VERSION + key).hexdigest()[:32]
    return cache_dir() / "reach" / f"{digest}.txt"


def _stored_reach(key: bytes) -> float | None:
    """The reach stored for this chain by an earlier process, if any (and readable)."""
    try:
        value = float(_reach_file(key).read_text().strip())
    except (OSError, ValueError):
        return None
    return value if math.isfinite(value) and value > 0.0 else None


def _store_reach(key: bytes, reach: float) -> None:
    """Store the reach of a chain (atomically; a folder that cannot be written is skipped)."""
    target = _reach_file(key)
    try:
        target.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(prefix=".reach-", suffix=".tmp", dir=target.parent)
    except OSError:
        return
    try:
        with os.fdopen(fd, "w") as fh:
            fh.write(repr(float(reach)) + "\n")
        os.replace(tmp, target)
    except OSError:
        Path(tmp).unlink(missing_ok=True)


def _six_rows(jacobian: np.ndarray) -> np.ndarray:
    """A Jacobian from Pinocchio as 6 x nv: Pinocchio gives the 6 x 1 Jacobian of a model with
    one degree of freedom as a flat vector of 6."""
    return np.asarray(jacobian, dtype=float).reshape(6, -1)


def _extract_chain(
    model: pin.Model, ids: list[int], base_link: str, tip_link: str, source: str
) -> tuple[list[ChainJoint], np.ndarray, np.ndarray]:
    """Placements, kinds, axes and limits of the joints ``ids`` (base to tip) of ``model``.

    Joints outside the chain stay at their neutral values; only the placement of the base
    link depends on them.
    """
    tip = model.frames[model.getFrameId(tip_link, pin.FrameType.BODY)]
    data = model.createData()
    q0 = pin.neutral(model)
    pin.framesForwardKinematics(model, data, q0)
    base_world = data.oMf[model.getFrameId(base_link, pin.FrameType.BODY)]
    chain: list[ChainJoint] = []
    for k, jid in enumerate(ids):
        jm = model.joints[jid]
        name = model.names[jid]
        if jm.nv != 1:
            raise KinematicsError(
                f"{source}: joint {name!r} ({jm.shortname()}) has {jm.nv} degrees of freedom; "
                "an arm chain may hold revolute, continuous and prismatic joints only"
            )
        motion = _six_rows(pin.computeJointJacobian(model, data, q0, jid))[:, jm.idx_v]
        lin, ang = motion[:3], motion[3:]
        if np.linalg.norm(ang) > 1e-12 and np.linalg.norm(lin) < 1e-12:
            kind, axis = "revolute", ang / np.linalg.norm(ang)
        elif np.linalg.norm(lin) > 1e-12 and np.linalg.norm(ang) < 1e-12:
            kind, axis = "prismatic", lin / np.linalg.norm(lin)
        else:
            raise KinematicsError(
                f"{source}: joint {name!r} ({jm.shortname()}) is neither revolute nor prismatic"
            )
        if jm.nq == 2:  # continuous joint, stored as (cos, sin)
            lower, upper = -math.pi, math.pi
        else:
            lower = float(model.lowerPositionLimit[jm.idx_q])
            upper = float(model.upperPositionLimit[jm.idx_q])
            if lower < -_WIDE or upper > _WIDE or lower >= upper:
                if kind == "prismatic":
                    raise KinematicsError(
                        f"{source}: prismatic joint {name!r} has no usable limits"
                    )
                lower, upper = -math.pi, math.pi
        placement = model.jointPlacements[jid]
        if k == 0:
            placement = base_world.inverse() * data.oMi[model.parents[jid]] * placement
        chain.append(
            ChainJoint(
                name=name,
                kind=kind,
                axis=np.array(axis, dtype=float),
                rotation=np.array(placement.rotation, dtype=float),
                translation=np.array(placement.translation, dtype=float),
                lower=lower,
                upper=upper,
            )
        )
    return chain, np.array(tip.placement.rotation), np.array(tip.placement.translation)
