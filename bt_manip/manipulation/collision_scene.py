"""A planning scene for an arm: its links and the obstacles around it, as collision shapes.

:class:`CollisionScene` reads a URDF with Pinocchio (kinematics and collision geometry), keeps
only the joints it plans for (every other joint is locked at a given value), and checks
configurations with coal through ``pin.computeCollisions`` (mesh paths resolved as for
PyBullet, :func:`~bt_manip.sim.compose.composed_urdf`):

- the robot's links: each configuration is checked first on the convex hulls of the collision
  meshes (a hull contains its mesh, so a configuration free for the hulls is free for the
  meshes), and only when the hulls touch, again on the meshes themselves, so every answer holds
  for the exact meshes at the cost of the hulls for free configurations (``exact=True`` checks
  the meshes only); primitives as they are, optionally grown by ``padding`` metres;
- self-collision between links, except the pairs an allowed-collision matrix allows: adjacent
  links, the pairs an SRDF disables (``disable_collisions``), and those found never to touch
  over sampled configurations (:func:`never_colliding_pairs`, as MoveIt's setup assistant
  finds them);
- obstacles (boxes, cylinders, spheres) with a pose in the model's root frame, which can be
  moved (:meth:`CollisionScene.move_obstacle`) to keep the scene in step with a world.

Every check is counted (:attr:`CollisionScene.checks`): planners budget in checks, never in
wall time, so their outcomes do not depend on the machine.
"""

from __future__ import annotations

import contextlib
import functools
import hashlib
import itertools
import math
import os
import re
import tempfile
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path

import coal
import defusedxml.ElementTree as SafeET
import numpy as np
import pinocchio as pin

from bt_manip.cache import Memo, bytes_key
from bt_manip.kinematics.arm_model import write_configuration
from bt_manip.sim.compose import cache_dir, composed_urdf, file_stamp

__all__ = [
    "CollisionScene",
    "Obstacle",
    "SceneError",
    "named_contacts",
    "never_colliding_pairs",
    "srdf_pairs",
]


HULL_MARGIN = 1e-4
"""Gap (m) under which the hull pass counts two shapes as touching and asks the meshes. coal's
GJK, stopping on its tolerance, can report a shallow contact of a hull (a convex shape) with a
cylinder as a gap of a few nanometres; the margin keeps the hull pass from calling free what
the meshes touch."""


class SceneError(ValueError):
    """A URDF, SRDF or obstacle the scene cannot be built from; the message says why."""


@dataclass(frozen=True)
class Obstacle:
    """A shape in the model's root frame: ``box`` (x, y, z sizes), ``cylinder`` (radius,
    length along its z), ``sphere`` (radius) or ``convex`` (the hull of ``points``, in the
    obstacle's frame); ``pose`` is a 4x4 transform."""

    name: str
    shape: str
    size: tuple[float, ...]
    pose: tuple[tuple[float, ...], ...]
    points: tuple[tuple[float, float, float], ...] = ()


def _shape(kind: str, size: Sequence[float], padding: float = 0.0,
           points: Sequence[Sequence[float]] = ()) -> coal.CollisionGeometry:
    if kind == "convex" and len(points) >= 4:
        vertices = coal.StdVec_Vec3s()
        for point in np.asarray(points, dtype=float):
            vertices.append(point)
        hull = coal.Convex.convexHull(vertices, False, "")
        if padding > 0.0:
            hull.setSweptSphereRadius(padding)
        return hull
    if kind == "box" and len(size) == 3:
        return coal.Box(*(float(s) + 2.0 * padding for s in size))
    if kind == "cylinder" and len(size) == 2:
        return coal.Cylinder(float(size[0]) + padding, float(size[1]) + 2.0 * padding)
    if kind == "sphere" and len(size) == 1:
        return coal.Sphere(float(size[0]) + padding)
    raise SceneError(f"obstacle shape {kind!r} with {len(size)} size value(s): use box (3), "
                     "cylinder (radius, length), sphere (radius) or convex (4 points or more)")


def _se3(pose: Sequence[Sequence[float]] | np.ndarray) -> pin.SE3:
    m = np.asarray(pose, dtype=float)
    return pin.SE3(m[:3, :3], m[:3, 3])


_LOADED: Memo[tuple[pin.Model, pin.GeometryModel]] = Memo(8)
"""Models and collision geometry read in this process, by URDF bytes."""
_HULLS: Memo[tuple[pin.Model, pin.GeometryModel]] = Memo(8)
"""Models and collision geometry with each mesh replaced by its convex hull, by URDF bytes."""
_MESH_FILE = re.compile(rb'filename\s*=\s*"([^"]+)"')


def _key(urdf: Path, package_dirs: tuple[str, ...]) -> bytes:
    """The URDF's bytes, the folders its meshes are looked up in, and each mesh file's stamp:
    what the geometry read from it depends on."""
    data = urdf.read_bytes()
    stamps = [repr(file_stamp(m.decode(errors="replace").removeprefix("file://")))
              for m in _MESH_FILE.findall(data)]
    return data + repr(package_dirs).encode() + "".join(stamps).encode()


def _loaded(urdf: Path, package_dirs: tuple[str, ...]) -> tuple[pin.Model, pin.GeometryModel]:
    """The URDF's model and its collision geometry with the meshes themselves."""
    key = bytes_key(_key(urdf, package_dirs))
    known = _LOADED.get(key)
    if known is None:
        full = pin.buildModelFromUrdf(str(urdf))
        dirs = [str(urdf.resolve().parent), *package_dirs]
        try:
            geometry = pin.buildGeomFromUrdf(full, str(urdf), pin.COLLISION, package_dirs=dirs)
        except (ValueError, RuntimeError) as exc:
            raise SceneError(f"{urdf}: collision geometry does not load: {exc}") from None
        known = (full, geometry)
        _LOADED.put(key, known)
    return known[0], known[1].clone()


def _age(path: Path) -> float:
    try:
        return path.stat().st_mtime
    except OSError:
        return 0.0


def _read(path: Path) -> pin.GeometryModel | None:
    """The geometry saved at ``path``; None when there is none (or it does not read)."""
    if not path.is_file():
        return None
    geometry = pin.GeometryModel()
    try:
        geometry.loadFromBinary(str(path))
    except (RuntimeError, ValueError):
        return None  # a damaged file is made again
    return geometry


JOINT_SUFFIX = "#joint"
"""Added, while the planning model is reduced, to the name of a joint named like a link."""


def _distinct_joint_names(full: pin.Model) -> pin.Model:
    """``full``, or a copy of it whose joints and joint frames named like a link carry
    :data:`JOINT_SUFFIX` (ANYmal C's ``RF_KFE`` is a joint and a link, so is the SO-100's
    ``gripper``; the B1's arm has a fixed joint and a link ``gripperStator``): Pinocchio's model
    reduction looks frames up by name and stops at two of one name."""
    links = {f.name for f in full.frames if f.type == pin.FrameType.BODY}
    clash = links & ({full.names[i] for i in range(1, full.njoints)}
                     | {f.name for f in full.frames if f.type != pin.FrameType.BODY})
    if not clash:
        return full
    full = pin.Model(full)
    for i in range(1, full.njoints):
        if full.names[i] in clash:
            full.names[i] = full.names[i] + JOINT_SUFFIX
    for i in range(len(full.frames)):
        frame = full.frames[i]
        if frame.type != pin.FrameType.BODY and frame.name in clash:
            frame.name = frame.name + JOINT_SUFFIX
            full.frames[i] = frame
    return full


def _plain(name: str) -> str:
    """A joint's name without :data:`JOINT_SUFFIX`."""
    return name.removesuffix(JOINT_SUFFIX)


def _hulls(urdf: Path, package_dirs: tuple[str, ...]) -> tuple[pin.Model, pin.GeometryModel]:
    """The URDF's model and its collision geometry with every mesh replaced by its convex
    hull. Reading meshes and building their bounding-volume trees is most of what a scene
    costs to make (a quarter of a second for the UR3 on the Husky), and a hull pass needs
    neither: the hulls are kept in the cache folder and read back in milliseconds; the meshes
    are read only when a check needs them."""
    raw = _key(urdf, package_dirs)
    key = bytes_key(raw)
    known = _HULLS.get(key)
    if known is None:
        path = cache_dir() / f"hulls-{hashlib.sha256(raw).hexdigest()[:24]}.bin"
        hulls = _read(path)
        if hulls is None:
            _, hulls = _loaded(urdf, package_dirs)
            for g in hulls.geometryObjects:
                shape = g.geometry
                if isinstance(shape, coal.BVHModelBase):
                    # the convex hull itself: buildConvexRepresentation keeps the mesh's
                    # vertices and faces as they are, whose support search gets stuck on a
                    # concave mesh and can find it free where the mesh touches
                    try:
                        shape.buildConvexHull(True, "Qt")
                    except RuntimeError:
                        # qhull gives up on some meshes ("Too many neighbors": Centauro's
                        # pelvis); a joggled hull (QJ) of the same points is built instead
                        shape.buildConvexHull(True, "QJ")
                    g.geometry = shape.convex
            _save(hulls, path)
        known = (pin.buildModelFromUrdf(str(urdf)), hulls)
        _HULLS.put(key, known)
    return known[0], known[1].clone()


_EXACT_REQUEST = coal.CollisionRequest()
PAIRWISE_CONFIRMS = 16
"""Hull contacts a scene confirms pair by pair, reading only the meshes involved, before it
reads every mesh of the robot and confirms through the broad phase."""
_MESHES: Memo[coal.BVHModelOBBRSS] = Memo(64)
"""Collision meshes read in this process, by file, stamp and scale."""


def _from_mesh(g: pin.GeometryObject) -> bool:
    """Whether ``g``'s shape is the convex hull of a mesh (read from a file)."""
    return bool(g.meshPath) and isinstance(g.geometry, coal.ConvexBase)


def _mesh(path: str, scale: tuple[float, ...]) -> coal.BVHModelOBBRSS:
    """The mesh at ``path`` scaled by ``scale``, indexed for collision tests as a URDF's meshes
    are (kept in the cache folder: read back in a tenth of the time)."""
    raw = f"{path}|{file_stamp(path)}|{scale}".encode()
    key = bytes_key(raw)
    known = _MESHES.get(key)
    if known is None:
        cached = cache_dir() / f"mesh-{hashlib.sha256(raw).hexdigest()[:24]}.bin"
        known = coal.BVHModelOBBRSS()
        try:
            known.loadFromBinary(str(cached))
        except (RuntimeError, ValueError, OSError):
            known = coal.MeshLoader().load(path, np.asarray(scale, dtype=float))
            _save(known, cached)
        _MESHES.put(key, known)
    return known


CACHE_FILES_KEPT = 64
"""Files of each kind (hulls, meshes) kept in the cache folder; the oldest go first."""


def _save(geometry: pin.GeometryModel | coal.CollisionGeometry, path: Path) -> None:
    """Write ``geometry`` to ``path`` so that other processes see the whole file or none; the
    oldest files of its kind beyond :data:`CACHE_FILES_KEPT` are removed."""
    path.parent.mkdir(parents=True, exist_ok=True)
    kind = path.name.split("-", 1)[0]
    others = sorted(path.parent.glob(f"{kind}-*.bin"), key=_age)
    for old in others[: max(0, len(others) - CACHE_FILES_KEPT + 1)]:
        with contextlib.suppress(OSError):
            old.unlink()
    fd, tmp = tempfile.mkstemp(prefix=f".{path.stem}-", suffix=".tmp", dir=path.parent)
    os.close(fd)
    try:
        geometry.saveToBinary(tmp)
        os.replace(tmp, path)
    finally:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(tmp)


def named_contacts(pairs: Sequence[tuple[str, str]], most: int = 4) -> str:
    """``a touches b, c touches d``: the first ``most`` pairs in contact, for a reason."""
    return ", ".join(f"{a} touches {b}" for a, b in pairs[:most])


def srdf_pairs(path: Path) -> set[frozenset[str]]:
    """The link pairs an SRDF's ``disable_collisions`` elements allow to touch."""
    try:
        root = SafeET.parse(str(path)).getroot()
    except Exception as exc:  # defusedxml and expat raise several unrelated types
        raise SceneError(f"{path}: the SRDF does not parse: {exc}") from None
    return {
        frozenset((el.get("link1", ""), el.get("link2", "")))
        for el in root.iter("disable_collisions")
    }


class CollisionScene:
    """Collision checks of one arm's configurations against itself and its obstacles."""

    def __init__(
        self,
        urdf: Path,
        joints: Sequence[str],
        locked: dict[str, float] | None = None,
        allowed: Iterable[frozenset[str]] = (),
        padding: float = 0.0,
        exact: bool = False,
        package_dirs: Sequence[str] = (),
    ) -> None:
        urdf = composed_urdf(urdf)  # mesh paths made absolute, as PyBullet loads them
        self._source = (Path(urdf), tuple(package_dirs))
        full, geometry = (_loaded if exact else _hulls)(*self._source)
        full = _distinct_joint_names(full)
        names = [_plain(full.names[i]) for i in range(1, full.njoints)]
        missing = [j for j in joints if j not in names]
        if missing:
            raise SceneError(f"{urdf}: no joint {missing} (joints: {', '.join(names)})")
        q0 = pin.neutral(full)
        for name, value in (locked or {}).items():
            if name in names:
                joint = full.joints[names.index(name) + 1]
                if joint.nq == 2:  # a continuous joint: its angle as (cos, sin)
                    q0[joint.idx_q:joint.idx_q + 2] = (math.cos(value), math.sin(value))
                else:
                    q0[joint.idx_q] = value
        lock = [i + 1 for i, n in enumerate(names) if n not in joints]
        self._reduce = (full, lock, q0)
        self.model, self.geometry = pin.buildReducedModel(full, geometry, lock, q0)
        for i in range(1, self.model.njoints):
            self.model.names[i] = _plain(self.model.names[i])
        self.joint_names = tuple(self.model.names[i] for i in range(1, self.model.njoints))
        order = [self.joint_names.index(j) for j in joints]
        if order != sorted(order) or self.model.nv != len(joints):
            raise SceneError("the planned joints must be one-axis joints listed in URDF order")
        # a continuous joint is stored as (cos, sin) in Pinocchio's configuration; the scene
        # takes its angle, within -pi .. pi as the arm's kinematics gives it
        self._slots = [(self.model.joints[i].idx_q, self.model.joints[i].nq)
                       for i in range(1, self.model.njoints)]
        self._turning = any(nq == 2 for _, nq in self._slots)
        self.lower = np.array([-math.pi if nq == 2 else float(self.model.lowerPositionLimit[s])
                               for s, nq in self._slots])
        self.upper = np.array([math.pi if nq == 2 else float(self.model.upperPositionLimit[s])
                               for s, nq in self._slots])
        self._robot_geoms = self.geometry.ngeoms
        self.exact = exact
        """Whether the scene checks the meshes only (no hull pass)."""
        self._meshes: pin.GeometryModel | None = None
        self._confirms = 0
        # per robot shape, what the exact pass tests: the primitive as the URDF gives it, or
        # the mesh a hull stands for (read when first needed)
        self._exact_shape: list[coal.CollisionGeometry | None] = [
            None if _from_mesh(g) else g.geometry.clone() for g in self.geometry.geometryObjects
        ]
        self._mesh_source = [(g.meshPath, tuple(float(v) for v in g.meshScale))
                             for g in self.geometry.geometryObjects]
        if padding > 0.0:
            for g in self.geometry.geometryObjects:
                if not isinstance(g.geometry, coal.BVHModelBase):
                    g.geometry = _padded(g.geometry, padding)
        self.link_of = [self._link_name(g) for g in self.geometry.geometryObjects]
        self.allowed = set(allowed) | self._adjacent()
        for i, j in itertools.combinations(range(self._robot_geoms), 2):
            a, b = self.link_of[i], self.link_of[j]
            if a != b and frozenset((a, b)) not in self.allowed:
                self._add_pair(i, j)
        self.obstacles: dict[str, int] = {}
        self.held: dict[str, int] = {}
        self.data = self.model.createData()
        self._mesh_data = self.model.createData()
        self._changed()
        self.checks = 0
        """Configurations checked so far."""

    def _link_name(self, g: pin.GeometryObject) -> str:
        frame = self.model.frames[g.parentFrame] if g.parentFrame < len(self.model.frames) else None
        return str(frame.name) if frame is not None else str(g.name).rsplit("_", 1)[0]

    def _adjacent(self) -> set[frozenset[str]]:
        """Link pairs joined by one joint (through fixed frames): always allowed to touch."""
        out: set[frozenset[str]] = set()
        bodies: dict[int, list[str]] = {}
        for f in self.model.frames:
            if f.type == pin.FrameType.BODY:
                bodies.setdefault(f.parentJoint, []).append(f.name)
        for jid in range(1, self.model.njoints):
            parent = self.model.parents[jid]
            for a in bodies.get(parent, []):
                for b in bodies.get(jid, []):
                    out.add(frozenset((a, b)))
        for links in bodies.values():  # links rigidly joined by fixed joints
            for a, b in itertools.combinations(links, 2):
                out.add(frozenset((a, b)))
        return out

    def _geometries(self) -> list[pin.GeometryModel]:
        """The geometries every change goes to: the first pass's, and the meshes' once read."""
        return [self.geometry] + ([self._meshes] if self._meshes is not None else [])

    @property
    def mesh_geometry(self) -> pin.GeometryModel | None:
        """The same shapes with the collision meshes themselves, where the first pass has their
        hulls (None for an exact scene, whose first pass has the meshes): a configuration the
        hulls find in contact is confirmed on these, so a check answers for the exact meshes.
        Read on first use, with the obstacles, held objects and pairs of the first pass."""
        if self.exact:
            return None
        if self._meshes is None:
            full, lock, q0 = self._reduce
            _, meshes = pin.buildReducedModel(full, _loaded(*self._source)[1], lock, q0)
            for g in list(self.geometry.geometryObjects)[self._robot_geoms:]:
                meshes.addGeometryObject(pin.GeometryObject(
                    g.name, g.parentJoint, g.parentFrame, g.placement, g.geometry.clone()))
            for pair in self.geometry.collisionPairs:
                meshes.addCollisionPair(pin.CollisionPair(pair.first, pair.second))
            self._meshes = meshes
            self._fresh_meshes()
        return self._meshes

    def _add_pair(self, i: int, j: int) -> None:
        for geometry in self._geometries():
            geometry.addCollisionPair(pin.CollisionPair(i, j))

    def _changed(self) -> None:
        """The shapes or pairs changed: the geometry data and broad phase are made again
        before the next check (once, however many changes came before it)."""
        self._stale = True

    def _fresh(self) -> None:
        """Fresh geometry data and broad phase if the shapes or pairs changed. The broad
        phase culls pairs by their bounding boxes before the exact test (about five times fewer
        microseconds per check than testing every pair for the Panda among six boxes)."""
        if not self._stale:
            return
        self._stale = False
        self._gdata = pin.GeometryData(self.geometry)
        if not self.exact:
            for request in self._gdata.collisionRequests:
                request.security_margin = HULL_MARGIN
        self._broad = pin.BroadPhaseManager_NaiveCollisionManager(
            self.model, self.geometry, self._gdata
        )
        if self._meshes is not None:
            self._fresh_meshes()

    def _fresh_meshes(self) -> None:
        assert self._meshes is not None
        self._mesh_gdata = pin.GeometryData(self._meshes)
        self._mesh_broad = pin.BroadPhaseManager_NaiveCollisionManager(
            self.model, self._meshes, self._mesh_gdata
        )

    @property
    def gdata(self) -> pin.GeometryData:
        """The geometry data of the first (hull) pass, up to date."""
        self._fresh()
        return self._gdata

    @property
    def mesh_gdata(self) -> pin.GeometryData:
        """The geometry data of the mesh pass, up to date (a scene with meshes only has none)."""
        self._fresh()
        if self.mesh_geometry is None:
            raise SceneError("an exact scene has no mesh pass")
        return self._mesh_gdata

    def allow(self, pairs: Iterable[frozenset[str]]) -> None:
        """Stop checking these pairs of links (or link and obstacle)."""
        pairs = set(pairs)
        self.allowed |= pairs
        for geometry in self._geometries():
            # indices copied first: the pairs pinocchio lists are views into its vector, which
            # shift under them as pairs are removed
            for i, j in [(p.first, p.second) for p in geometry.collisionPairs]:
                if frozenset((self.link_of[i], self.link_of[j])) in pairs:
                    geometry.removeCollisionPair(pin.CollisionPair(i, j))
        self._changed()

    # -- obstacles ----------------------------------------------------------------------------
    def add_obstacle(self, obstacle: Obstacle, padding: float = 0.0) -> None:
        """Add a shape checked against every robot link (the pairs allowed aside)."""
        self.add_obstacles([obstacle], padding)

    def add_obstacles(self, obstacles: Sequence[Obstacle], padding: float = 0.0,
                      allowed: Iterable[frozenset[str]] = ()) -> None:
        """Add several obstacles at once (the broad phase is rebuilt once); ``allowed``: pairs
        of a link and an obstacle left unchecked besides the scene's own."""
        allowed = self.allowed | set(allowed)
        for obstacle in obstacles:
            if obstacle.name in self.obstacles:
                raise SceneError(f"obstacle '{obstacle.name}' is already in the scene")
            shape = _shape(obstacle.shape, obstacle.size, padding, obstacle.points)
            for geometry in self._geometries():
                index = geometry.addGeometryObject(pin.GeometryObject(
                    f"obstacle:{obstacle.name}", 0, 0, _se3(obstacle.pose), shape.clone()
                ))
            self.obstacles[obstacle.name] = index
            self.link_of.append(obstacle.name)
            for i in [*range(self._robot_geoms), *self.held.values()]:
                if frozenset((self.link_of[i], obstacle.name)) not in allowed:
                    self._add_pair(i, index)
        self._changed()

    def hold(self, obstacle: Obstacle, link: str, touching: Iterable[str] = ()) -> None:
        """Carry ``obstacle`` with ``link``: its ``pose`` is then in ``link``'s frame, it moves
        with the arm and is checked against the obstacles and the robot's links, except the
        ``touching`` links (the fingers and hand holding it). Call before adding obstacles."""
        if self.obstacles:
            raise SceneError("hold objects before adding obstacles (clear_obstacles first)")
        frame_id = self.model.getFrameId(link, pin.FrameType.BODY)
        if frame_id >= len(self.model.frames):
            raise SceneError(f"no link '{link}' in the planning model")
        frame = self.model.frames[frame_id]
        shape = _shape(obstacle.shape, obstacle.size, 0.0, obstacle.points)
        placement = frame.placement * _se3(obstacle.pose)
        for geometry in self._geometries():
            index = geometry.addGeometryObject(pin.GeometryObject(
                f"held:{obstacle.name}", frame.parentJoint, frame_id, placement, shape.clone()
            ))
        self.held[obstacle.name] = index
        self.link_of.append(obstacle.name)
        allowed = set(touching)
        for i in range(self._robot_geoms):
            if self.link_of[i] not in allowed:
                self._add_pair(i, index)
        self._changed()

    def clear_obstacles(self) -> None:
        """Remove every obstacle and held object (the robot's own shapes stay)."""
        if not self.obstacles and not self.held:
            return
        for geometry in self._geometries():
            for name in self.obstacles:
                geometry.removeGeometryObject(f"obstacle:{name}")
            for name in self.held:
                geometry.removeGeometryObject(f"held:{name}")
        self.link_of = self.link_of[: self._robot_geoms]
        self.obstacles = {}
        self.held = {}
        self._changed()

    def move_obstacle(self, name: str, pose: Sequence[Sequence[float]] | np.ndarray) -> None:
        """Put obstacle ``name`` at ``pose`` (4x4, root frame)."""
        index = self.obstacles[name]
        for geometry in self._geometries():
            geometry.geometryObjects[index].placement = _se3(pose)
        self._changed()

    # -- checks -------------------------------------------------------------------------------
    def collides(self, q: np.ndarray) -> bool:
        """True when configuration ``q`` puts two shapes in contact (one check)."""
        self.checks += 1
        self._fresh()
        return self._hit(np.asarray(q, dtype=float))

    def hulls_touch(self, q: np.ndarray) -> bool:
        """True when the first pass (the hulls, or the meshes of an exact scene) finds a
        contact at ``q``, without asking the meshes (one check). A configuration whose hulls
        are free is free for the meshes inside them; one whose hulls touch may still be free
        for the meshes (:meth:`collides` answers that)."""
        self.checks += 1
        self._fresh()
        return bool(pin.computeCollisions(self.model, self.data, self._broad,
                                          self.pin_q(np.asarray(q, dtype=float)), True))

    def pin_q(self, q: np.ndarray) -> np.ndarray:
        """Pinocchio's configuration of the planning model for joint values ``q`` (one a
        joint): ``q`` itself unless a joint is continuous (its angle as (cos, sin))."""
        if not self._turning:
            return q
        return write_configuration(np.empty(self.model.nq), self._slots, q)

    def _hit(self, q: np.ndarray) -> bool:
        """Whether ``q`` is in contact (the caller has made the data fresh)."""
        return self._hit_pin(self.pin_q(q))

    def _hit_pin(self, q: np.ndarray) -> bool:
        """:meth:`_hit` of Pinocchio's configuration ``q``."""
        if not pin.computeCollisions(self.model, self.data, self._broad, q, True):
            return False  # the hulls are free: so are the meshes inside them
        if self.exact:
            return True
        if self._meshes is not None:
            return bool(pin.computeCollisions(self.model, self._mesh_data, self._mesh_broad, q,
                                              True))
        self._confirms += 1
        if self._confirms > PAIRWISE_CONFIRMS:
            self.mesh_geometry  # noqa: B018 (read now: many confirms to come)
            return self._hit_pin(q)
        return self._confirmed(q)

    def _confirmed(self, q: np.ndarray) -> bool:  # q: Pinocchio's configuration
        """After the hulls touched at ``q``: whether the shapes themselves do. A mesh lies
        inside its hull, so only the pairs whose hulls touch can touch; each is tested again
        with the robot's meshes (each read the first time it is needed) and primitives. (Once
        a scene has confirmed :data:`PAIRWISE_CONFIRMS` contacts, it reads every mesh and
        confirms on all of them through the broad phase, which is faster when contacts are
        many, as in a planner's search.)"""
        gdata = self._gdata
        pin.computeCollisions(self.model, self.data, self.geometry, gdata, q, False)
        results = gdata.collisionResults
        for k, pair in enumerate(self.geometry.collisionPairs):
            if results[k].isCollision():
                i, j = pair.first, pair.second
                a, b = gdata.oMg[i], gdata.oMg[j]
                result = coal.CollisionResult()
                if coal.collide(self._exact(i), coal.Transform3s(a.rotation, a.translation),
                                self._exact(j), coal.Transform3s(b.rotation, b.translation),
                                _EXACT_REQUEST, result):
                    return True
        return False

    def _exact(self, index: int) -> coal.CollisionGeometry:
        """The shape the exact pass tests for geometry ``index``."""
        if index >= self._robot_geoms:  # an obstacle or a held object: as it is
            shape: coal.CollisionGeometry = self.geometry.geometryObjects[index].geometry
            return shape
        known = self._exact_shape[index]
        if known is None:
            path, scale = self._mesh_source[index]
            known = self._exact_shape[index] = _mesh(path, scale)
        return known

    def contacts(self, q: np.ndarray) -> list[tuple[str, str]]:
        """Every pair of links (or link and obstacle) in contact at ``q``, by name."""
        self._fresh()
        geometry, gdata = ((self.mesh_geometry, self._mesh_gdata)
                           if self.mesh_geometry is not None else (self.geometry, self._gdata))
        pin.computeCollisions(self.model, self._mesh_data, geometry, gdata,
                              self.pin_q(np.asarray(q, dtype=float)), False)
        out: list[tuple[str, str]] = []
        for k, pair in enumerate(geometry.collisionPairs):
            named = (self.link_of[pair.first], self.link_of[pair.second])
            if gdata.collisionResults[k].isCollision() and named not in out:
                out.append(named)
        return out

    def first_blocked(self, waypoints: Sequence[np.ndarray], step: float) -> np.ndarray | None:
        """The first configuration in contact along ``waypoints`` (the first one included),
        each segment straight in joint space and checked no more than ``step`` rad per joint
        apart, in path order; None when the whole path is free."""
        self._fresh()
        hit = self._hit
        first = np.asarray(waypoints[0], dtype=float)
        self.checks += 1
        if hit(first):
            return first
        for a, b in itertools.pairwise(np.asarray(w, dtype=float) for w in waypoints):
            n = max(1, math.ceil(float(np.max(np.abs(b - a))) / step))
            for k in range(1, n + 1):
                q: np.ndarray = a + (b - a) * (k / n)
                self.checks += 1
                if hit(q):
                    return q
        return None

    def segment_free(self, a: np.ndarray, b: np.ndarray, step: float,
                     hulls_only: bool = False) -> bool:
        """True when every configuration from ``a`` to ``b`` (straight in joint space, no joint
        moving more than ``step`` rad between two checks) is free; ``a`` itself is not checked.
        Checked from the middle outwards, which finds a blocked segment sooner. With
        ``hulls_only``, a configuration whose hulls touch counts as blocked without asking the
        meshes: a stricter answer (never free where the meshes touch), several times cheaper
        near obstacles."""
        n = max(1, math.ceil(float(np.abs(b - a).max()) / step))
        self._fresh()
        if hulls_only:
            model, data, broad = self.model, self.data, self._broad
            collisions = pin.computeCollisions

            def hit(q: np.ndarray) -> bool:
                return bool(collisions(model, data, broad, self.pin_q(q), True))
        else:
            hit = self._hit
        # the end first (as the bisection order has it): most blocked segments stop here,
        # before the others are computed
        self.checks += 1
        if hit(b):
            return False
        if n == 1:
            return True
        configs = a + np.multiply.outer(_fractions(n)[1:], b - a)
        for k, q in enumerate(configs):
            if hit(q):
                self.checks += k + 1
                return False
        self.checks += n - 1
        return True

    def within_limits(self, q: np.ndarray) -> bool:
        return bool(np.all(q >= self.lower - 1e-9) and np.all(q <= self.upper + 1e-9))


@functools.lru_cache(maxsize=512)
def _bisection_order(n: int) -> tuple[int, ...]:
    """1 .. n, the end first, then the middles of ever smaller intervals."""
    order = [n]
    seen = {0, n}
    intervals = [(0, n)]
    while intervals:
        nxt = []
        for lo, hi in intervals:
            if hi - lo < 2:
                continue
            mid = (lo + hi) // 2
            if mid not in seen:
                seen.add(mid)
                order.append(mid)
            nxt += [(lo, mid), (mid, hi)]
        intervals = nxt
    order += [k for k in range(1, n) if k not in seen]
    return tuple(order)


@functools.lru_cache(maxsize=512)
def _fractions(n: int) -> np.ndarray:
    """:func:`_bisection_order` as fractions of the segment (read-only)."""
    out = np.asarray(_bisection_order(n), dtype=float) / n
    out.flags.writeable = False
    return out


def _padded(shape: coal.CollisionGeometry, padding: float) -> coal.CollisionGeometry:
    """A primitive grown by ``padding`` (convex hulls are kept: coal has no offset hull)."""
    if isinstance(shape, coal.Box):
        return coal.Box(*(2.0 * shape.halfSide + 2.0 * padding))
    if isinstance(shape, coal.Sphere):
        return coal.Sphere(shape.radius + padding)
    if isinstance(shape, coal.Cylinder):
        return coal.Cylinder(shape.radius + padding, 2.0 * shape.halfLength + 2.0 * padding)
    if isinstance(shape, coal.Capsule):
        return coal.Capsule(shape.radius + padding, 2.0 * shape.halfLength)
    return shape


def never_colliding_pairs(
    scene: CollisionScene, samples: int = 2000, seed: int = 0
) -> set[frozenset[str]]:
    """Self-collision pairs that touch in none of ``samples`` random configurations (seeded):
    pairs a planner may leave out, as MoveIt's setup assistant writes them to an SRDF."""
    rng = np.random.default_rng(seed)
    lo = np.where(np.isfinite(scene.lower), scene.lower, -math.pi)
    hi = np.where(np.isfinite(scene.upper), scene.upper, math.pi)
    pairs = [
        (k, p) for k, p in enumerate(scene.geometry.collisionPairs)
        if p.first < scene._robot_geoms and p.second < scene._robot_geoms
    ]
    touched = np.zeros(len(pairs), dtype=bool)
    gdata = scene.gdata
    for _ in range(samples):
        q = scene.pin_q(rng.uniform(lo, hi))
        pin.computeCollisions(scene.model, scene.data, scene.geometry, gdata, q, False)
        for n, (k, _) in enumerate(pairs):
            if not touched[n] and gdata.collisionResults[k].isCollision():
                touched[n] = True
    return {
        frozenset((scene.link_of[p.first], scene.link_of[p.second]))
        for n, (_, p) in enumerate(pairs)
        if not touched[n]
    }
