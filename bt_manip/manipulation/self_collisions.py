"""The arm's allowed-collision matrix: the pairs of its own links the planner never checks.

A planner that checked every pair of links would find the arm in collision where nothing is
wrong: links that meet at a joint overlap by design, and a folded pose (a tuck over the base)
brings meshes together that the robot's makers accept. As MoveIt's setup assistant does, the
pairs are sorted by why they may be left out:

- ``adjacent``: links joined by one joint (or rigidly joined). The planning scene allows these
  by itself (:class:`~bt_manip.manipulation.collision_scene.CollisionScene`); they are not
  written down.
- ``default``: pairs in contact in one of the descriptor's named arm states (``home``,
  ``tuck``, ...) on the exact meshes: the states are poses the robot is meant to take, so what
  touches there is accepted.
- ``never``: pairs apart in every one of many random configurations within the joint limits
  (seeded, on the convex hulls, which are larger than the meshes): the arm's reach cannot bring
  them together, so checking them costs time for nothing.

:func:`find_allowed_collisions` finds them; ``bt-manip robot init`` writes them into the
descriptor's ``planning.allowed_collisions`` (:func:`planning_section`), which the planner then
reads (an SRDF's ``disable_collisions`` may be added with ``planning.srdf``).
"""

from __future__ import annotations

import json
from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np

from bt_manip.manipulation.collision_scene import CollisionScene, never_colliding_pairs
from bt_manip.sim.compose import write_atomic_bytes
from bt_manip.sim.robot_description import ALLOWED_REASONS, RobotDescription, load_description
from bt_manip.sim.yaml_lines import load_yaml

__all__ = [
    "SELF_SAMPLES",
    "AllowedCollisions",
    "add_planning_section",
    "find_allowed_collisions",
    "planning_section",
]

SELF_SAMPLES = 1000
"""Random configurations sampled to find the link pairs that never touch."""

Pair = frozenset[str]


@dataclass(frozen=True)
class AllowedCollisions:
    """Pairs of the arm's links allowed to touch, by reason (see the module docstring)."""

    default: frozenset[Pair] = frozenset()
    never: frozenset[Pair] = frozenset()
    user: frozenset[Pair] = frozenset()

    @classmethod
    def of(cls, desc: RobotDescription) -> AllowedCollisions | None:
        """The pairs ``desc`` lists (None when it lists none)."""
        listed = desc.planning.allowed
        if listed is None:
            return None
        return cls(*(listed.get(reason, frozenset()) for reason in ALLOWED_REASONS))

    @property
    def pairs(self) -> frozenset[Pair]:
        """Every allowed pair, whatever its reason."""
        return self.default | self.never | self.user

    def by_reason(self) -> dict[str, frozenset[Pair]]:
        return {"default": self.default, "never": self.never, "user": self.user}


def find_allowed_collisions(
    desc: RobotDescription, samples: int = SELF_SAMPLES, seed: int = 0
) -> AllowedCollisions:
    """The ``default`` and ``never`` pairs of ``desc``'s arm (the joints that are not the arm's
    held at zero, the fingers included)."""
    scene = CollisionScene(desc.urdf_path, list(desc.arm.joints))
    default: set[Pair] = set()
    for q in desc.states.values():
        default |= {frozenset(pair) for pair in scene.contacts(np.asarray(q, dtype=float))}
    never = never_colliding_pairs(scene, samples, seed) - default
    return AllowedCollisions(frozenset(default), frozenset(never))


def _pair_lines(reason: str, pairs: Iterable[Pair], comment: str) -> list[str]:
    rows = sorted(tuple(sorted(p)) for p in pairs)
    if not rows:
        return [f"    {reason}: []  # {comment}"]
    return [f"    {reason}:  # {comment}"] + [
        f"      - [{json.dumps(a)}, {json.dumps(b)}]" for a, b in rows
    ]


def planning_section(allowed: AllowedCollisions, padding: float, samples: int) -> str:
    """The descriptor's ``planning`` section (YAML text) for ``allowed`` and ``padding``."""
    lines = [
        "planning:",
        f"  padding: {padding:g}  # m the world's shapes grow by when a path is planned",
        "  allowed_collisions:  # pairs of the arm's links never checked against each other",
        *_pair_lines("default", allowed.default, "touching in a named state"),
        *_pair_lines("never", allowed.never, f"apart in {samples} sampled configurations"),
    ]
    if allowed.user:
        lines += _pair_lines("user", allowed.user, "listed by hand")
    return "\n".join(lines) + "\n"


def add_planning_section(desc: RobotDescription, samples: int = SELF_SAMPLES
                         ) -> tuple[RobotDescription, AllowedCollisions]:
    """Find ``desc``'s allowed collisions and append them as its ``planning`` section (a
    descriptor without one); returns the descriptor read again and what was found."""
    if "planning" in load_yaml(desc.path):
        raise ValueError(f"{desc.path} has a planning section already")
    allowed = find_allowed_collisions(desc, samples)
    text = desc.path.read_text(encoding="utf-8")
    text = (text if text.endswith("\n") else text + "\n") + planning_section(
        allowed, desc.planning.padding, samples)
    write_atomic_bytes(desc.path, text.encode("utf-8"))
    return load_description(desc.path), allowed
