"""The World: a world file built into a PyBullet simulation with its own clock.

``World(path, seed=...)`` reads a world file (:mod:`bt_manip.sim.world_reader`), connects a private
PyBullet client in DIRECT mode, builds walls, furniture, movable objects and robots, and then
only moves when :meth:`World.step` is called. The sim clock advances by one physics period per
step, so everything timed against it is independent of the wall clock, and the same seed gives
the same run bit for bit.

Randomisation (:mod:`bt_manip.sim.randomize`): each object or robot with a ``randomize`` range
gets offsets drawn from a generator seeded by (world seed, entity name), so adding an entity does
not change the others. Groups (:mod:`bt_manip.sim.groups`) move their members, named poses
included, by one rigid motion per seed before anything is built; ``World.spec`` is the world
file so placed.

Movable objects at rest sleep (see :data:`SLEEP_THRESHOLD`): Bullet leaves them out of the
solver until a moving body touches them or is fixed to them, and removing a body wakes them all.
"""

from __future__ import annotations

import contextlib
import math
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import pybullet as pb

from bt_manip.clock import ManualClock
from bt_manip.errors import InputError, Problem
from bt_manip.geometry import euler_from_quat, quat_from_euler, quat_from_yaw, rotation_matrix
from bt_manip.sim import pybullet_queries as pbq
from bt_manip.sim.assets import shipped_or_given
from bt_manip.sim.attach import Attachments
from bt_manip.sim.events import BodyAdded, BodyRemoved, WorldEvents
from bt_manip.sim.randomize import Rigid2D, entity_rng, place_groups, sample_offset
from bt_manip.sim.robot import Robot, RobotDescription
from bt_manip.sim.static_bodies import make_static
from bt_manip.sim.world_reader import parse_world
from bt_manip.sim.world_spec import BodySpec, Part, Pose2D, Pose3D, WallSpec, WorldSpec

if TYPE_CHECKING:
    from bt_manip.sim.robot import Robot

OVERLAP_TOLERANCE = 0.002
"""Penetration (m) between two bodies at spawn beyond which they are reported as overlapping."""
SLEEP_THRESHOLD = 1e-5
"""A movable object sleeps once its squared speeds (m^2/s^2 + rad^2/s^2 summed) stay below this
for two seconds of sim time (Bullet's sleeping): about 3 mm/s, some 25 times the jitter of a
panel resting in its stand and far below anything moving. A sleeping object costs the solver
nothing; a contact or constraint with a moving body wakes it."""


@dataclass
class BodyInfo:
    """What the World knows about a body it made."""

    name: str
    body_id: int
    kind: str  # "ground" | "wall" | "furniture" | "object" | "robot"
    spec: Any
    line: int


def _half(part: Part) -> list[float]:
    return [part.size[0] / 2, part.size[1] / 2, part.size[2] / 2]


def _shape_args(part: Part, visual: bool = False) -> dict[str, Any]:
    """Keyword arguments of createCollisionShape (or createVisualShape) for one primitive."""
    if part.shape == "box":
        return {"shapeType": pb.GEOM_BOX, "halfExtents": _half(part)}
    if part.shape == "cylinder":
        return {
            "shapeType": pb.GEOM_CYLINDER,
            "radius": part.size[0],
            "length" if visual else "height": part.size[2],
        }
    return {"shapeType": pb.GEOM_SPHERE, "radius": part.size[0]}


def _volume(part: Part) -> float:
    if part.shape == "box":
        return part.size[0] * part.size[1] * part.size[2]
    if part.shape == "cylinder":
        return math.pi * part.size[0] ** 2 * part.size[2]
    return 4.0 / 3.0 * math.pi * part.size[0] ** 3


class World:
    """A loaded world: PyBullet client, named bodies, robots, named poses and the sim clock.

    Args:
        path: the world file (YAML).
        seed: picks the randomised starts; the same seed gives the same run.
        gui: open PyBullet's own window instead of DIRECT mode (needs a display).
    """

    def __init__(self, path: str | Path, seed: int = 0, *, gui: bool = False) -> None:
        self.spec: WorldSpec
        self.group_moves: dict[str, Rigid2D]
        """Each group's rigid motion for this seed (the spec's members are already moved)."""
        # a relative path that names no file here but a shipped world is that world, as on
        # the command line
        path = shipped_or_given(str(path))
        self.spec, self.group_moves = place_groups(parse_world(path), int(seed))
        self.path = Path(path)
        self.seed = int(seed)
        self.rate_hz = self.spec.physics.rate_hz
        self.dt = 1.0 / self.rate_hz
        self.clock = ManualClock()
        self.step_count = 0
        self.gui = gui
        self.client = pb.connect(pb.GUI if gui else pb.DIRECT)
        pbq.forget_collision_shapes(self.client)  # of an earlier client with this id
        self.infos: dict[str, BodyInfo] = {}
        self.robots: dict[str, Robot] = {}
        self.poses: dict[str, Pose2D] = dict(self.spec.poses)
        self.models: dict[str, BodySpec] = {m.name: m for m in self.spec.models}
        self.events = WorldEvents()
        """Bodies added and removed, attach and detach, announced while the world runs."""
        self.attachments = Attachments(self)
        self.fastened_to: dict[int, str] = {}
        """The structure each fastening joint holds an object to, by constraint id
        (:mod:`bt_manip.sim.fasteners`)."""
        try:
            self._setup_physics()
            self._build()
        except BaseException:
            self.close()
            raise

    # -- construction ----------------------------------------------------------------------
    def _setup_physics(self) -> None:
        c = self.client
        ph = self.spec.physics
        pb.resetSimulation(physicsClientId=c)
        pb.setTimeStep(self.dt, physicsClientId=c)
        pb.setGravity(*ph.gravity, physicsClientId=c)
        pb.setPhysicsEngineParameter(
            numSolverIterations=ph.solver_iterations,
            enableConeFriction=0,
            deterministicOverlappingPairs=1,
            physicsClientId=c,
        )
        if ph.solver_tolerance is not None:
            pb.setPhysicsEngineParameter(
                solverResidualThreshold=ph.solver_tolerance**2, physicsClientId=c
            )
        plane = {"shapeType": pb.GEOM_PLANE}
        ground = make_static(c, False, plane, self._ground_visual(), [0.0, 0.0, 0.0])
        pb.changeDynamics(ground, -1, lateralFriction=ph.ground_friction, physicsClientId=c)
        self.infos["ground"] = BodyInfo("ground", ground, "ground", None, 0)

    def _ground_visual(self) -> int:
        """The ground's visual shape: PyBullet's own (a large checkered plane) in its window;
        headless, a transparent 1 mm box at the origin. Nothing in bt-manip draws the ground
        from PyBullet's visuals (the viewer and the replay page draw their own floor), and
        PyBullet takes some 5 ms to make its plane visual for every world built. The ground's
        collision shape, and so the physics, are the same either way."""
        if self.gui:
            return -1  # PyBullet makes its plane visual from the collision shape
        return int(pb.createVisualShape(
            pb.GEOM_BOX, halfExtents=[0.0005] * 3, rgbaColor=[0.0, 0.0, 0.0, 0.0],
            physicsClientId=self.client,
        ))

    def _build(self) -> None:
        problems: list[Problem] = []
        for wall in self.spec.walls:
            self._add(wall.name, self._make_wall(wall), "wall", wall, wall.line)
        for body in self.spec.furniture:
            self._add(
                body.name, self._make_body(body, (0.0, 0.0, 0.0)), "furniture", body, body.line
            )
        for body in self.spec.objects:
            offset = sample_offset(entity_rng(self.seed, body.name), body.randomize)
            self._add(body.name, self._make_body(body, offset), "object", body, body.line)
        for rspec in self.spec.robots:
            try:
                robot = self._make_robot(rspec)
            except InputError as exc:
                problems += [
                    Problem(str(self.path), rspec.line, f"robot '{rspec.name}': {p}")
                    for p in exc.problems
                ]
                continue
            self.robots[rspec.name] = robot
            self._add(rspec.name, robot.body, "robot", rspec, rspec.line)
        problems += self._overlaps()
        if problems:
            raise InputError(problems)

    def _add(self, name: str, body_id: int, kind: str, spec: Any, line: int) -> None:
        self.infos[name] = BodyInfo(name, body_id, kind, spec, line)

    def _make_wall(self, wall: WallSpec) -> int:
        """One static body per wall: a box for each solid stretch between doors."""
        c = self.client
        (x0, y0), (x1, y1) = wall.start, wall.end
        length = wall.length
        ux, uy = (x1 - x0) / length, (y1 - y0) / length
        yaw = math.atan2(uy, ux)
        stretches: list[tuple[float, float]] = []
        pos = 0.0
        for door in wall.doors:
            lo = door.at - door.width / 2
            if lo > pos + 1e-6:
                stretches.append((pos, lo))
            pos = door.at + door.width / 2
        if length > pos + 1e-6:
            stretches.append((pos, length))
        quat = quat_from_yaw(yaw)
        halves = [[(b - a) / 2, wall.thickness / 2, wall.height / 2] for a, b in stretches]
        # frames are relative to the wall's start point, along the wall's axis
        frames = [[(a + b) / 2, 0.0, wall.height / 2] for a, b in stretches]
        n = len(stretches)
        shape = {
            "shapeTypes": [pb.GEOM_BOX] * n,
            "halfExtents": halves,
            "collisionFramePositions": frames,
        }
        vis = pb.createVisualShapeArray(
            [pb.GEOM_BOX] * n, halfExtents=halves, visualFramePositions=frames, physicsClientId=c
        )
        body = make_static(c, True, shape, vis, [x0, y0, 0.0], quat)
        pb.changeVisualShape(body, -1, rgbaColor=wall.colour, physicsClientId=c)
        return int(body)

    def _make_body(self, spec: BodySpec, offset: tuple[float, float, float]) -> int:
        c = self.client
        pos, quat = self._placed_pose(spec, offset)
        if spec.urdf is not None:
            try:
                body = pb.loadURDF(
                    str(spec.urdf),
                    pos,
                    quat,
                    useFixedBase=not spec.movable,
                    globalScaling=spec.scale,
                    physicsClientId=c,
                )
            except pb.error:
                raise InputError.single(
                    str(self.path), spec.line,
                    f"'{spec.name}': PyBullet cannot load its URDF {spec.urdf} (check its links "
                    "and meshes)") from None
            why = pbq.too_many_links(c, body)
            if why is not None:
                raise InputError.single(str(self.path), spec.line,
                                        f"'{spec.name}': {why} ({spec.urdf})")
        else:
            body = self._make_compound(spec, pos, quat)
        if spec.movable:
            for link in range(-1, pbq.joint_count(c, body)):
                pb.changeDynamics(body, link, lateralFriction=spec.friction, physicsClientId=c)
            pb.changeDynamics(
                body, -1, activationState=pb.ACTIVATION_STATE_ENABLE_SLEEPING,
                sleepThreshold=SLEEP_THRESHOLD, physicsClientId=c,
            )
        return int(body)

    def _placed_pose(
        self, spec: BodySpec, offset: tuple[float, float, float]
    ) -> tuple[list[float], list[float]]:
        x, y, z = spec.pose.xyz
        yaw0 = euler_from_quat(spec.pose.quat)
        quat = list(spec.pose.quat)
        if offset[2] != 0.0:
            quat = list(quat_from_euler((yaw0[0], yaw0[1], yaw0[2] + offset[2])))
        if spec.planar and spec.parts:
            z = -min(p.bottom() for p in spec.parts) * spec.scale
        return [x + offset[0], y + offset[1], z], quat

    def _make_compound(self, spec: BodySpec, pos: list[float], quat: list[float]) -> int:
        c = self.client
        s = spec.scale
        parts = [
            Part(
                p.shape,
                (p.size[0] * s, p.size[1] * s, p.size[2] * s),
                (p.xyz[0] * s, p.xyz[1] * s, p.xyz[2] * s),
                p.rpy,
                p.colour,
            )
            for p in spec.parts
        ]
        volumes = [_volume(p) for p in parts]
        com = (
            np.average([p.xyz for p in parts], axis=0, weights=volumes)
            if spec.movable
            else np.zeros(3)
        )
        array = not (
            len(parts) == 1 and parts[0].rpy == (0.0, 0.0, 0.0) and parts[0].xyz == (0.0, 0.0, 0.0)
        )
        shape: dict[str, Any]
        if not array:
            shape = _shape_args(parts[0])
            vis = pb.createVisualShape(
                **_shape_args(parts[0], visual=True),
                rgbaColor=parts[0].colour or spec.colour,
                physicsClientId=c,
            )
        else:
            types = [_shape_args(p)["shapeType"] for p in parts]
            sizes = {
                "radii": [p.size[0] for p in parts],
                "halfExtents": [_half(p) for p in parts],
                "lengths": [p.size[2] for p in parts],
            }
            frames = [list(np.subtract(p.xyz, com)) for p in parts]
            orns = [list(quat_from_euler(p.rpy)) for p in parts]
            shape = {
                "shapeTypes": types, "collisionFramePositions": frames,
                "collisionFrameOrientations": orns, **sizes,
            }
            vis = pb.createVisualShapeArray(
                types, visualFramePositions=frames, visualFrameOrientations=orns, **sizes,
                physicsClientId=c,
            )
        # the body frame sits at the centre of mass; shift the spawn point to match
        rot = rotation_matrix(quat)
        base = np.asarray(pos) + rot @ com
        if spec.movable:
            make = pb.createCollisionShapeArray if array else pb.createCollisionShape
            col = make(**shape, physicsClientId=c)
            body = pb.createMultiBody(spec.mass, col, vis, list(base), quat, physicsClientId=c)
        else:
            body = make_static(c, array, shape, vis, list(base), quat)
        pb.changeVisualShape(body, -1, rgbaColor=spec.colour, physicsClientId=c)
        return int(body)

    def _make_robot(self, rspec: Any) -> Any:
        desc = RobotDescription.load(rspec.description_path)
        dx, dy, dyaw = sample_offset(entity_rng(self.seed, rspec.name), rspec.randomize)
        pose = rspec.pose
        robot = Robot.spawn(self.client, desc, pose.x + dx, pose.y + dy, pose.yaw + dyaw)
        if rspec.arm_state is not None:
            states = getattr(desc, "states", {}) or {}
            if rspec.arm_state not in states:
                raise InputError.single(
                    str(self.path),
                    rspec.line,
                    f"unknown arm_state '{rspec.arm_state}'; known: {', '.join(states) or 'none'}",
                )
            robot.reset_arm(states[rspec.arm_state])
        return robot

    def _penetration(self, a: int, b: int) -> float:
        """Signed distance (m) between two bodies where they touch; negative when overlapping."""
        pts = pbq.closest_points(self.client, a, b, 0.0)
        return min((p.distance for p in pts), default=0.0)

    def _overlaps(self) -> list[Problem]:
        """Movable objects and robots must not start inside anything else."""
        problems = []
        movers = [i for i in self.infos.values() if i.kind in ("object", "robot")]
        others = [i for i in self.infos.values() if i.kind != "ground"]
        reported: set[frozenset[str]] = set()
        for a in movers:
            for b in others:
                pair = frozenset((a.name, b.name))
                if a.name == b.name or pair in reported:
                    continue
                depth = self._penetration(a.body_id, b.body_id)
                if depth < -OVERLAP_TOLERANCE:
                    reported.add(pair)
                    line = max(a.line, b.line)
                    problems.append(
                        Problem(
                            str(self.path),
                            line,
                            f"'{a.name}' and '{b.name}' overlap by {-depth * 1000:.0f} mm "
                            "at spawn; move one of them apart",
                        )
                    )
        return problems

    # -- running ------------------------------------------------------------------------------
    def step(self, n: int = 1) -> None:
        """Advance physics by ``n`` periods of ``dt`` and the sim clock with it."""
        step, client, clock, dt = pb.stepSimulation, self.client, self.clock, self.dt
        if not self.attachments.any():
            # nothing attaches while physics steps: with nothing held there are no contacts
            # to record, and nothing reads the clock between these steps
            for _ in range(n):
                step(physicsClientId=client)
            self.step_count += n
            clock.t = self.step_count * dt
            return
        record_contacts = self.attachments.record_contacts
        for _ in range(n):
            step(physicsClientId=client)
            self.step_count += 1
            clock.t = self.step_count * dt
            record_contacts()

    @property
    def time(self) -> float:
        """Sim time in seconds since the world was built."""
        return self.clock.now()

    # -- changing the world while it runs --------------------------------------------------
    def spawn_model(self, name: str) -> int:
        """Add the model ``name`` declared in the world file's ``models``, at its pose plus
        the offset its ``randomize`` ranges draw for this world's seed; returns its id.

        Raises KeyError for an unknown model, ValueError as :meth:`spawn` does.
        """
        spec = self.models.get(name)
        if spec is None:
            known = ", ".join(sorted(self.models)) or "none"
            raise KeyError(f"no model named '{name}' in {self.path.name}; models: {known}")
        return self.spawn(spec, sample_offset(entity_rng(self.seed, name), spec.randomize))

    def spawn(self, spec: BodySpec, offset: tuple[float, float, float] = (0.0, 0.0, 0.0)) -> int:
        """Add a body while the world runs (movable if ``spec.movable``), moved by ``offset``
        (x, y, yaw); returns its id and announces :class:`~bt_manip.sim.events.BodyAdded`.

        Raises ValueError when the name is taken or the body would start inside another
        (nothing is added then, and nothing is announced).
        """
        if spec.name in self.infos:
            raise ValueError(f"a body named '{spec.name}' already exists")
        kind = "object" if spec.movable else "furniture"
        body = self._make_body(spec, offset)
        for info in list(self.infos.values()):
            if info.kind == "ground":
                continue
            depth = self._penetration(body, info.body_id)
            if depth < -OVERLAP_TOLERANCE:
                pb.removeBody(body, physicsClientId=self.client)
                pbq.forget_collision_shapes(self.client, body)
                raise ValueError(
                    f"'{spec.name}' would start {-depth * 1000:.0f} mm inside '{info.name}'"
                )
        self._add(spec.name, body, kind, spec, spec.line)
        self.events.announce(BodyAdded(self.time, spec.name, body, kind, spec))
        return body

    def remove(self, name: str) -> None:
        """Take a movable object or piece of furniture out of the world (and out of the hand);
        announces :class:`~bt_manip.sim.events.BodyRemoved` (after the detach, if held)."""
        info = self.infos.get(name)
        if info is None or info.kind not in ("object", "furniture"):
            known = sorted(i.name for i in self.infos.values() if i.kind in ("object", "furniture"))
            raise KeyError(f"no object or furniture named '{name}'; known: {', '.join(known)}")
        if self.attachments.is_attached(name):
            self.attachments.detach(name)
        pb.removeBody(info.body_id, physicsClientId=self.client)
        pbq.forget_collision_shapes(self.client, info.body_id)
        del self.infos[name]
        self._wake_movables()  # whatever rested on the body removed must fall
        self.events.announce(BodyRemoved(self.time, name, info.body_id, info.kind))

    def _wake_movables(self) -> None:
        """Wake every sleeping movable object (a body removed wakes nothing by itself)."""
        for info in self.infos.values():
            if info.kind == "object":
                pb.changeDynamics(
                    info.body_id, -1, activationState=pb.ACTIVATION_STATE_WAKE_UP,
                    physicsClientId=self.client,
                )

    # -- queries ------------------------------------------------------------------------------
    def body_id(self, name: str) -> int:
        """The PyBullet id of a named body; KeyError naming the known ones otherwise."""
        if name not in self.infos:
            raise KeyError(
                f"no body named '{name}' in {self.path.name}; known: "
                f"{', '.join(sorted(self.infos))}"
            )
        return self.infos[name].body_id

    def name_of(self, body_id: int) -> str | None:
        for info in self.infos.values():
            if info.body_id == body_id:
                return info.name
        return None

    def obstacle_body_ids(self) -> list[int]:
        """Static structure and furniture: what navigation must keep clear of."""
        return [i.body_id for i in self.infos.values() if i.kind in ("wall", "furniture")]

    @property
    def movable(self) -> dict[str, int]:
        """Movable objects by name."""
        return {i.name: i.body_id for i in self.infos.values() if i.kind == "object"}

    def body_pose(self, name: str) -> Pose3D:
        """World pose of a body's base (centre of mass frame, as PyBullet reports it)."""
        pos, quat = pb.getBasePositionAndOrientation(
            self.body_id(name), physicsClientId=self.client
        )
        return Pose3D(tuple(pos), tuple(quat))  # type: ignore[arg-type]

    def snapshot(self) -> dict[str, Any]:
        """Every body's base pose and velocity and every joint state, exactly as floats."""
        c = self.client
        out: dict[str, Any] = {"time": self.time}
        for info in self.infos.values():
            if info.kind in ("ground", "wall", "furniture"):
                continue
            b = info.body_id
            pos, quat = pb.getBasePositionAndOrientation(b, physicsClientId=c)
            lin, ang = pb.getBaseVelocity(b, physicsClientId=c)
            joints = [
                (s.position, s.velocity)
                for s in pbq.joint_states(c, b, list(range(pbq.joint_count(c, b))))
            ]
            out[info.name] = {"pos": pos, "quat": quat, "lin": lin, "ang": ang, "joints": joints}
        return out

    def summary(self) -> str:
        """A few lines describing the world for the console."""
        kinds: dict[str, int] = {}
        for info in self.infos.values():
            kinds[info.kind] = kinds.get(info.kind, 0) + 1
        lines = [
            f"world '{self.spec.name}' ({self.path}), seed {self.seed}, "
            f"{self.rate_hz:g} Hz physics",
            f"  {kinds.get('wall', 0)} walls, {kinds.get('furniture', 0)} furniture, "
            f"{kinds.get('object', 0)} movable objects, {len(self.models)} models to spawn, "
            f"{len(self.robots)} robots",
        ]
        for name, robot in self.robots.items():
            x, y, yaw = robot.base_pose2d()
            lines.append(
                f"  robot {name} ({robot.description.name}) at "
                f"x={x:.3f} y={y:.3f} yaw={math.degrees(yaw):.1f} deg"
            )
        for name, move in self.group_moves.items():
            lines.append(
                f"  group {name} moved by dx={move.dx:.3f} dy={move.dy:.3f} "
                f"dyaw={math.degrees(move.dyaw):.1f} deg about "
                f"({move.origin[0]:.3f}, {move.origin[1]:.3f})"
            )
        if self.poses:
            lines.append("  named poses: " + ", ".join(sorted(self.poses)))
        return "\n".join(lines)

    # -- teardown --------------------------------------------------------------------------------
    def close(self) -> None:
        """Disconnect the PyBullet client (idempotent)."""
        if getattr(self, "client", None) is not None and self.client >= 0:
            pbq.forget_collision_shapes(self.client)
            with contextlib.suppress(pb.error):
                pb.disconnect(physicsClientId=self.client)
            self.client = -1

    def __enter__(self) -> World:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def __del__(self) -> None:
        self.close()
