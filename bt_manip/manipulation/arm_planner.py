"""The planning scene of one robot's arm, kept in step with its world, and its plans.

:class:`ArmPlanner` builds a :class:`~bt_manip.manipulation.collision_scene.CollisionScene` from
the robot's URDF (the one PyBullet loaded): the arm joints are planned, every other joint
(wheels, a holonomic base's virtual joints, fingers, a head) is locked where it is. Before each
plan it is brought up to date with the world (:meth:`ArmPlanner.sync`):

- every body near the arm (walls, furniture, the floor, movable objects where they are now),
  in the frame of the robot's root link;
- the objects the robot holds (attach joints), carried by the link that holds them and allowed
  to touch the fingers and the hand;
- the object about to be grasped, allowed to touch the fingers and the hand.

Robot links that no arm joint moves are never tested against the world (the wheels stand on the
floor; nothing the arm does changes that). A scene is built per setting of the locked joints
(rounded to a millimetre or a milliradian), so opening the gripper builds another; a few are
kept. Plans are :func:`~bt_manip.manipulation.rrt_connect.plan_steps` generators: a node
advances one a few thousand checks per tick.
"""

from __future__ import annotations

import hashlib
import itertools
import json
import math
from collections import OrderedDict
from collections.abc import Generator
from dataclasses import dataclass
from typing import Any

import numpy as np
import pinocchio as pin
import pybullet as pb

from bt_manip.geometry import inverse_matrix
from bt_manip.manipulation.collision_scene import CollisionScene, Obstacle, srdf_pairs
from bt_manip.manipulation.rrt_connect import PlanOptions, PlanResult, plan_steps
from bt_manip.manipulation.self_collisions import (
    SELF_SAMPLES,
    AllowedCollisions,
    find_allowed_collisions,
)
from bt_manip.manipulation.world_obstacles import body_obstacles, world_obstacles
from bt_manip.sim.compose import cache_dir, write_atomic_bytes
from bt_manip.sim.randomize import entity_rng
from bt_manip.sim.robot_description import RobotDescription

__all__ = ["PLANNERS", "ArmPlanner", "allowed_pairs"]

PLANNERS = ("auto", "rrtconnect", "none")
"""``auto``: plan only when the direct joint move would collide; ``rrtconnect``: always plan
(a free direct move is the plan); ``none``: move directly, as without a planner."""
SCENES_KEPT = 4
REACH_MARGIN = 0.5
"""m added to the arm's reach when choosing the bodies near enough to matter."""


@dataclass(frozen=True)
class _World:
    """The world as a scene takes it: objects carried (in their link's frame, with the link),
    the other shapes (root frame), the link-shape pairs allowed, the links that may touch what
    the hand holds."""

    carried: list[tuple[Obstacle, str]]
    shapes: list[Obstacle]
    allowed: set[frozenset[str]]
    touching: set[str]


class ArmPlanner:
    """Plans of one robot's arm in one world (see the module docstring)."""

    def __init__(self, world: Any, robot: Any, robot_name: str) -> None:
        self.world = world
        self.robot = robot
        self.robot_name = robot_name
        self._scenes: OrderedDict[tuple[tuple[str, float], ...], CollisionScene] = OrderedDict()
        self._allowed: set[frozenset[str]] | None = None
        self.options = PlanOptions(max_checks=60_000)
        self.plans = 0
        """Plans started."""
        self.samples = 0
        """Samples drawn by the plans that ended."""
        self.wall_time = 0.0
        """Wall-clock seconds spent planning (for the run report; never for a decision)."""

    # -- the scene ----------------------------------------------------------------------------
    def _locked(self) -> dict[str, float]:
        arm = set(self.robot.description.arm.joints)
        out = {}
        for name, index in self.robot._joints.items():
            info = self.robot._joint_info[index]
            if name in arm or info.type not in (pb.JOINT_REVOLUTE, pb.JOINT_PRISMATIC):
                continue
            q = float(pb.getJointState(self.robot.body, index,
                                       physicsClientId=self.robot.client)[0])
            out[name] = round(q, 3)
        return out

    def scene(self) -> CollisionScene:
        """The scene for the locked joints as they are now (built on first use)."""
        locked = self._locked()
        key = tuple(sorted(locked.items()))
        scene = self._scenes.get(key)
        if scene is None:
            desc = self.robot.description
            scene = CollisionScene(desc.urdf_path, list(desc.arm.joints), locked=locked)
            if self._allowed is None:
                self._allowed = allowed_pairs(desc)
            scene.allow(self._allowed)
            self._scenes[key] = scene
            while len(self._scenes) > SCENES_KEPT:
                self._scenes.popitem(last=False)
        self._scenes.move_to_end(key)
        return scene

    def _root(self, scene: CollisionScene) -> np.ndarray:
        """World pose (4x4) of the planning model's root frame."""
        root = next(f.name for f in scene.model.frames if f.type == pin.FrameType.BODY)
        transform: np.ndarray = self.robot.link_transform(root)
        return transform

    def _reach(self, scene: CollisionScene) -> tuple[np.ndarray, float]:
        """A point at the arm's base (root frame) and how far the arm can reach from it."""
        model = scene.model
        base = model.jointPlacements[1].translation if model.njoints > 1 else np.zeros(3)
        reach = sum(float(np.linalg.norm(model.jointPlacements[j].translation))
                    for j in range(2, model.njoints))
        return np.asarray(base, dtype=float), reach + REACH_MARGIN

    def sync(self, scene: CollisionScene, grasping: str = "",
             ends: tuple[np.ndarray, ...] = (), padding: float = 0.0,
             movables: bool = True) -> None:
        """Bring ``scene`` up to date with the world (see the module docstring), its shapes
        grown by ``padding``. The contacts the arm has at the ``ends`` of a move (its start,
        and its goal once checked free without padding) are allowed for this plan: the arm may
        move away from what it touches, as a move without a plan may, and come as close to
        what the goal is close to. Without ``movables``, the world's movable objects are left
        out (a goal may brush one, as a move may push one)."""
        world = self._gather(scene, grasping, movables)
        self._place(scene, world, set(), padding)
        touching: set[frozenset[str]] = set()
        for q in ends:
            if scene.collides(np.asarray(q, dtype=float)):
                touching |= {frozenset(pair) for pair in scene.contacts(np.asarray(q, float))}
        if touching:
            self._place(scene, world, touching, padding)

    def _gather(self, scene: CollisionScene, grasping: str, movables: bool) -> _World:
        """What of the world goes into ``scene``, in its root frame (see :meth:`sync`)."""
        desc = self.robot.description
        hand = set(desc.gripper.finger_links) | {desc.end_effector, desc.grasp_link
                                                 or desc.grasp_frame}
        touching = hand | _hand(scene)
        world_from_root = self._root(scene)
        root_from_world = inverse_matrix(world_from_root)
        held = [(a.object_name, a.object_body, a.link_name)
                for a in self.world.attachments.held_by(self.robot_name)]
        carrier = desc.grasp_link or desc.grasp_frame
        held += [(name, body, carrier) for name, body in self.world.movable.items()
                 if name not in {h[0] for h in held} and self.robot.is_grasping(body)]
        carried = []
        for name, body, link in held:
            link_from_world = inverse_matrix(self.robot.link_transform(link))
            carried += [(_moved(shape, link_from_world), link)
                        for shape in body_obstacles(self.world.client, body, name)]
        base, reach = self._reach(scene)
        near = (world_from_root @ np.append(base, 1.0))[:3]
        skip = {h[0] for h in held}
        if not movables:
            skip |= set(self.world.movable) - {grasping}
        shapes = [_moved(o, root_from_world)
                  for o in world_obstacles(self.world, skip, near, reach)]
        static = {scene.link_of[i] for i in range(scene._robot_geoms)
                  if scene.geometry.geometryObjects[i].parentJoint == 0}
        allowed = {frozenset((link, o.name)) for o in shapes for link in static}
        if grasping:
            allowed |= {frozenset((link, o.name)) for o in shapes
                        if o.name == grasping or o.name.startswith(grasping + "#")
                        for link in touching}
        return _World(carried, shapes, allowed, touching)

    @staticmethod
    def _place(scene: CollisionScene, world: _World, extra: set[frozenset[str]],
               padding: float) -> None:
        """Put ``world`` into ``scene`` (what was there before taken out), ``extra`` pairs
        allowed besides the world's own."""
        scene.clear_obstacles()
        for shape, link in world.carried:
            scene.hold(shape, link, world.touching)
        scene.add_obstacles(world.shapes, padding, world.allowed | extra)

    def tool_path(self, path: list[np.ndarray], step: float = 0.05) -> np.ndarray:
        """World points (N x 3) the grasp frame passes along the joint ``path`` (straight
        segments sampled ``step`` rad apart at most): what the viewer draws of a plan."""
        scene = self.scene()
        model, data = scene.model, scene.model.createData()
        frame = model.getFrameId(self.robot.description.grasp_frame)
        if frame >= len(model.frames):
            frame = len(model.frames) - 1
        world_from_root = self._root(scene)
        points = []
        qs = [np.asarray(q, dtype=float) for q in path]
        for a, b in itertools.pairwise(qs):
            n = max(1, math.ceil(float(np.max(np.abs(b - a))) / step))
            for k in range(n + (b is qs[-1])):
                pin.framesForwardKinematics(model, data, scene.pin_q(a + (b - a) * (k / n)))
                p = world_from_root @ np.append(data.oMf[frame].translation, 1.0)
                points.append(p[:3])
        return np.asarray(points, dtype=float).reshape(-1, 3)

    # -- plans --------------------------------------------------------------------------------
    def direct_is_free(self, scene: CollisionScene, a: np.ndarray, b: np.ndarray) -> bool:
        """Whether the straight joint move is free, checked as finely as a plan's result."""
        return scene.segment_free(np.asarray(a, float), np.asarray(b, float),
                                  self.options.validate_step)

    def steps(self, scene: CollisionScene, start: np.ndarray, goal: np.ndarray, who: str
              ) -> Generator[int, None, PlanResult]:
        """The plan generator, seeded by the world's seed, ``who`` (the node) and a count."""
        self.plans += 1
        rng = entity_rng(self.world.seed, f"arm-plan:{who}:{self.plans}")
        return plan_steps(scene, np.asarray(start, float), np.asarray(goal, float), rng,
                          self.options)


def allowed_pairs(desc: RobotDescription) -> set[frozenset[str]]:
    """The pairs of ``desc``'s links the planner leaves out: those its descriptor lists (and its
    SRDF's), else the ones :func:`find_allowed_collisions` finds, kept in the cache folder
    (keyed by the URDF's bytes, the arm's joints and its named states)."""
    extra = srdf_pairs(desc.planning.srdf) if desc.planning.srdf is not None else set()
    listed = AllowedCollisions.of(desc)
    if listed is not None:
        return set(listed.pairs) | extra
    urdf = desc.urdf_path
    states = json.dumps(sorted((k, list(v)) for k, v in desc.states.items()))
    key = hashlib.sha256(urdf.read_bytes() + "\n".join(desc.arm.joints).encode()
                         + states.encode()).hexdigest()[:20]
    path = cache_dir() / f"allowed-pairs-{key}-{SELF_SAMPLES}.json"
    if path.is_file():
        try:
            return {frozenset(pair) for pair in json.loads(path.read_text())} | extra
        except (ValueError, TypeError):
            pass  # a damaged file is found again
    pairs = set(find_allowed_collisions(desc).pairs)
    write_atomic_bytes(path, json.dumps(sorted(sorted(p) for p in pairs)).encode())
    return pairs | extra


def _hand(scene: CollisionScene) -> set[str]:
    """The links the arm's last joint carries (the wrist's last link, the hand, the fingers
    locked in place): what may touch an object held or being grasped."""
    model = scene.model
    last = model.njoints - 1
    return {f.name for f in model.frames
            if f.type == pin.FrameType.BODY and f.parentJoint == last}


def _moved(obstacle: Obstacle, transform: np.ndarray) -> Obstacle:
    pose = transform @ np.asarray(obstacle.pose, dtype=float)
    return Obstacle(obstacle.name, obstacle.shape, obstacle.size,
                    tuple(tuple(float(v) for v in row) for row in pose), obstacle.points)

