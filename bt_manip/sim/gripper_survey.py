"""What ``bt-manip robot init`` learns of a gripper by moving it in PyBullet.

A URDF says which joints a hand has and their limits, not which way they close, how wide the
hand opens or which way it points. :func:`survey_gripper` finds out on the robot loaded in a
headless PyBullet client, every joint at its zero pose:

- closing direction: each finger joint is set to its lower and then its upper limit, and the
  centre of the collision shapes it moves (its link and every link below it) is measured from
  the grasp frame. The limit that brings them nearer is ``closed``. A joint that moves them less
  than :data:`MIN_TRAVEL` either way (it spreads fingers sideways, or moves a link without a
  real shape) cannot close on anything: named explicitly it is refused with that reason,
  matched by a pattern it is left out, and said so.
- kind: prismatic fingers make a ``parallel`` gripper (each joint a pad's distance from the
  centre line, so it must open as it grows); one or two revolute jaws a ``revolute`` gripper;
  more revolute joints a ``hand``. Mixed prismatic and revolute joints are refused.
- ``width`` of a revolute gripper or hand: the largest distance across the approach axis
  between two fingers' shapes when open (for a single jaw, how far its shapes move from closed
  to open).
- mimic joints: a joint that mimics a finger joint moves with it (PyBullet ignores ``mimic``),
  so it joins the gripper with its open and closed positions from the multiplier and offset.
- the approach axis (:func:`approach_axis`): the axis of the grasp frame pointing from the arm's
  last link to the grasp frame (or, when they coincide, to the fingers).
- links that enclose the grasp frame (:func:`enclosing_leaf_links`): a collision box around
  the whole hand (a planning "safety box") would hold every object off the fingers.
"""

from __future__ import annotations

import fnmatch
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Protocol

import numpy as np
import pybullet as pb

from bt_manip.sim import pybullet_queries as pbq

__all__ = [
    "MIN_TRAVEL",
    "GripperSurvey",
    "approach_axis",
    "enclosing_leaf_links",
    "expand_joint_patterns",
    "survey_gripper",
]

MIN_TRAVEL = 0.003
"""m a finger joint must move its shapes toward the grasp frame to count as closing."""
STRADDLE = 0.25
"""A revolute joint reaching more than this share of its range to each side of 0 spreads or
turns fingers rather than closing them."""


class JointLike(Protocol):
    """What the survey reads of a URDF joint."""

    @property
    def name(self) -> str: ...
    @property
    def type(self) -> str: ...
    @property
    def child(self) -> str: ...
    @property
    def lower(self) -> float: ...
    @property
    def upper(self) -> float: ...
    @property
    def velocity(self) -> float | None: ...
    @property
    def effort(self) -> float | None: ...


class SurveyError(ValueError):
    """The named joints cannot make a gripper; the message says why."""


@dataclass(frozen=True)
class GripperSurvey:
    """The gripper section ``robot init`` writes, and the notes it prints."""

    kind: str
    joints: tuple[str, ...]
    finger_links: tuple[str, ...]
    opens: tuple[float, ...]
    closeds: tuple[float, ...]
    width: float
    max_force: float
    max_speed: float
    notes: tuple[str, ...] = field(default=())


@dataclass
class Body:
    """A robot loaded in a PyBullet client: link and joint indices by name."""

    client: int
    body: int
    link_index: Mapping[str, int]
    joint_index: Mapping[str, int]
    below: Callable[[str], set[str]]
    """A link and every link under it."""
    has_shape: Callable[[str], bool]
    """Whether a link has a collision shape in the URDF."""

    def frame(self, link: str) -> tuple[np.ndarray, np.ndarray]:
        """World position and rotation (3x3) of a link frame."""
        index = self.link_index[link]
        if index < 0:
            pos, quat = pbq.com_pose(self.client, self.body, index)
        else:
            state = pbq.link_state(self.client, self.body, index)
            pos, quat = state.frame_position, state.frame_orientation
        rot = np.asarray(pb.getMatrixFromQuaternion(quat), dtype=float).reshape(3, 3)
        return np.asarray(pos, dtype=float), rot

    def set_joint(self, joint: str, value: float) -> None:
        pb.resetJointState(self.body, self.joint_index[joint], value, physicsClientId=self.client)

    def shape_centre(self, links: set[str]) -> np.ndarray | None:
        """Centre of the union of the links' collision boxes (None when none has a shape)."""
        boxes = [
            pb.getAABB(self.body, self.link_index[n], physicsClientId=self.client)
            for n in links
            if n in self.link_index and self.has_shape(n)
        ]
        if not boxes:
            return None
        lo = np.min([b[0] for b in boxes], axis=0)
        hi = np.max([b[1] for b in boxes], axis=0)
        centre: np.ndarray = (np.asarray(lo) + np.asarray(hi)) / 2.0
        return centre


def expand_joint_patterns(
    requested: Sequence[str], names: Sequence[str]
) -> tuple[list[str], set[str], list[str]]:
    """Joint names for ``--gripper`` items, in URDF order: each item a name or a shell pattern
    (``hand_*_flex_*``). Returns the names, those given by name, and items matching nothing."""
    out: list[str] = []
    explicit: set[str] = set()
    unmatched: list[str] = []
    for item in requested:
        if any(c in item for c in "*?["):
            found = [n for n in names if fnmatch.fnmatchcase(n, item)]
            if not found:
                unmatched.append(item)
            out += [n for n in found if n not in out]
        else:
            explicit.add(item)
            if item not in out:
                out.append(item)
    order = {n: i for i, n in enumerate(names)}
    out.sort(key=lambda n: order.get(n, len(order)))
    return out, explicit, unmatched


def _finger_links(body: Body, joint: JointLike) -> set[str]:
    return {n for n in body.below(joint.child) if body.has_shape(n)}


def _closing(body: Body, joint: JointLike, grasp: str) -> tuple[float, float, float] | str:
    """(open, closed, travel) of a finger joint, or the reason it does not close."""
    links = _finger_links(body, joint)
    if not links:
        return (f"it moves no link with a collision shape (link '{joint.child}' and those "
                "below it have none)")
    distances = []
    for value in (joint.lower, joint.upper):
        body.set_joint(joint.name, value)
        centre = body.shape_centre(links)
        distances.append(float(np.linalg.norm(centre - body.frame(grasp)[0]))
                         if centre is not None else 0.0)
    body.set_joint(joint.name, 0.0)
    travel = distances[0] - distances[1]
    if abs(travel) < MIN_TRAVEL:
        return (f"from its lower to its upper limit it moves its shapes "
                f"{abs(travel) * 1000:.1f} mm nearer to or farther from the grasp frame "
                f"'{grasp}' (a joint that spreads fingers sideways, or moves a link with no real "
                "shape), so it does not close on anything")
    span = joint.upper - joint.lower
    if joint.type == "revolute" and min(-joint.lower, joint.upper) > STRADDLE * span:
        return (f"its range {joint.lower:.3g} .. {joint.upper:.3g} rad reaches well to both "
                "sides of its zero pose, as a joint that spreads or turns fingers does; a "
                "closing joint travels one way from its rest")
    if travel > 0:  # the upper limit is nearer: closing as the joint grows
        return joint.lower, joint.upper, travel
    return joint.upper, joint.lower, -travel


def survey_gripper(
    body: Body,
    joints: Mapping[str, JointLike],
    mimics: Mapping[str, tuple[str, float, float]],
    requested: Sequence[str],
    explicit: set[str],
    grasp: str,
    approach: np.ndarray,
) -> GripperSurvey:
    """Kind, joints, open and closed positions and width of the gripper made of ``requested``
    joints (see the module docstring). ``mimics`` maps a follower joint to (leader, multiplier,
    offset); ``approach`` is the approach direction in the world. Raises :class:`SurveyError`."""
    notes: list[str] = []
    kept: list[tuple[JointLike, float, float]] = []
    for name in requested:
        joint = joints[name]
        if joint.type not in ("prismatic", "revolute"):
            raise SurveyError(f"joint '{name}' is {joint.type or 'untyped'}; a finger joint "
                              "must be prismatic or revolute")
        result = _closing(body, joint, grasp)
        if isinstance(result, str):
            if name in explicit:
                raise SurveyError(f"joint '{name}' cannot move a finger: {result}")
            notes.append(f"gripper: left out '{name}': {result}")
            continue
        kept.append((joint, result[0], result[1]))
    if not kept:
        raise SurveyError("none of the --gripper joints closes on anything (see above)")
    types = {j.type for j, _, _ in kept}
    if len(types) > 1:
        raise SurveyError("the --gripper joints mix prismatic and revolute joints: a gripper "
                          "is either parallel (prismatic) or turning (revolute)")
    names = {j.name for j, _, _ in kept}
    for follower, (leader, mult, offset) in mimics.items():
        if leader in names and follower not in names and follower in joints:
            lead = next(k for k in kept if k[0].name == leader)
            kept.append((joints[follower], mult * lead[1] + offset, mult * lead[2] + offset))
            notes.append(f"gripper: '{follower}' mimics '{leader}' and moves with it")
            names.add(follower)
    prismatic = types == {"prismatic"}
    if prismatic:
        kind = "parallel"
        reversed_ = [j.name for j, o, c in kept if o < c]
        if reversed_:
            raise SurveyError(
                f"prismatic finger joint(s) {reversed_} close as they grow; bt-manip reads a "
                "parallel finger joint as its pad's distance from the centre line (opening as "
                "it grows): flip the joint axis in the URDF"
            )
        if len({(o, c) for _, o, c in kept}) > 1:
            raise SurveyError("the prismatic finger joints have different limits; a parallel "
                              "gripper's fingers move as mirror images over the same stroke")
    else:
        kind = "revolute" if len(kept) <= 2 else "hand"
    fingers = _tips(body, [j for j, _, _ in kept])
    width = 0.0
    if not prismatic:
        width = _width(body, kept, grasp, approach)
    efforts = [j.effort for j, _, _ in kept if j.effort and j.effort > 0]
    speeds = [j.velocity for j, _, _ in kept if j.velocity and j.velocity > 0]
    unit = "m" if prismatic else "rad"
    closing = ", ".join(
        f"{j.name} {'+' if c > o else '-'}" for j, o, c in kept[:4]
    ) + (", ..." if len(kept) > 4 else "")
    notes.append(
        f"gripper: {kind}, {len(kept)} joint(s) ({unit}), closing toward the grasp frame as "
        f"measured ({closing})" + (f"; open width {width * 100:.1f} cm across the approach "
                                   "axis" if not prismatic else "")
    )
    return GripperSurvey(
        kind,
        tuple(j.name for j, _, _ in kept),
        tuple(fingers),
        tuple(o for _, o, _ in kept),
        tuple(c for _, _, c in kept),
        width,
        min(efforts, default=40.0),
        min(speeds, default=0.1 if prismatic else 1.0),
        tuple(notes),
    )


def _tips(body: Body, kept: list[JointLike]) -> list[str]:
    """The finger links: for each finger joint, the shaped links it moves that no other finger
    joint of the gripper moves further down (the distal ones), in joint order."""
    moved = {j.name: _finger_links(body, j) for j in kept}
    out: list[str] = []
    for j in kept:
        own = set(moved[j.name])
        for other in kept:
            if other.name != j.name and other.child in body.below(j.child):
                own -= moved[other.name]
        for link in sorted(own):
            if link not in out:
                out.append(link)
    return out


def _width(
    body: Body, kept: list[tuple[JointLike, float, float]], grasp: str, approach: np.ndarray
) -> float:
    """How wide the gripper opens, across the approach axis: the largest distance between two
    fingers' shapes when open; for a single jaw, how far its shapes move from closed to open."""
    axis = approach / max(float(np.linalg.norm(approach)), 1e-9)

    def across(points: list[np.ndarray]) -> list[np.ndarray]:
        return [p - float(np.dot(p, axis)) * axis for p in points]

    def centres(which: int) -> list[np.ndarray]:
        for joint, open_, closed in kept:
            body.set_joint(joint.name, (open_, closed)[which])
        out = [body.shape_centre(_finger_links(body, j)) for j, _, _ in kept]
        for joint, _, _ in kept:
            body.set_joint(joint.name, 0.0)
        return [c for c in out if c is not None]

    opened = across(centres(0))
    if len(opened) == 1:
        closed = across(centres(1))
        return float(np.linalg.norm(opened[0] - closed[0])) if closed else 0.0
    return max(
        (float(np.linalg.norm(a - b)) for i, a in enumerate(opened) for b in opened[i + 1:]),
        default=0.0,
    )


def approach_axis(
    body: Body, grasp: str, arm_tip: str, fingers: Sequence[str]
) -> tuple[str, str]:
    """The grasp frame's axis (``x``, ``-y``, ...) pointing from ``arm_tip`` to the grasp
    frame, or to the fingers' centre when the two frames coincide; and how it was found."""
    origin, rot = body.frame(grasp)
    tip = body.frame(arm_tip)[0]
    direction = origin - tip
    how = f"from '{arm_tip}' to '{grasp}'"
    if float(np.linalg.norm(direction)) < 0.005:
        centre = body.shape_centre(set(fingers))
        if centre is None:
            return "z", "assumed z (the grasp frame is on the arm tip and there are no fingers)"
        direction = centre - origin
        how = f"from '{grasp}' to the fingers"
    local = rot.T @ direction
    index = int(np.argmax(np.abs(local)))
    name = "xyz"[index]
    sign = "" if local[index] > 0 else "-"
    share = abs(float(local[index])) / max(float(np.linalg.norm(local)), 1e-9)
    angle = math.degrees(math.acos(min(1.0, share)))
    return f"{sign}{name}", (f"approach axis {sign}{name} of '{grasp}': the direction {how} "
                             f"({angle:.0f} deg off that axis)")


def enclosing_leaf_links(
    body: Body, grasp: str, leaves: Sequence[str], keep: set[str]
) -> list[str]:
    """Leaf links (not in ``keep``) whose collision box contains the grasp frame's origin."""
    origin = body.frame(grasp)[0]
    out = []
    for link in leaves:
        if link in keep or link not in body.link_index or not body.has_shape(link):
            continue
        lo, hi = pb.getAABB(body.body, body.link_index[link], physicsClientId=body.client)
        if np.all(np.asarray(lo) < origin) and np.all(origin < np.asarray(hi)):
            out.append(link)
    return out
