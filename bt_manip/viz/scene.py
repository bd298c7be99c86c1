"""A World as a meshcat scene: what to draw once, and which frames move.

:func:`build_scene` turns a loaded :class:`~bt_manip.sim.world.World` into a :class:`Scene`:

- every body gets a node ``/meshcat/bt_manip/<body name>`` placed at its base frame;
- robots and URDF bodies get one child node per link (``.../<body>/<link>``) placed relative to
  the body frame, holding that link's URDF visuals (meshes and primitives, URDF colours; a mesh
  without a URDF material keeps the colours of its file);
- walls, furniture and objects made of primitives draw their parts with the colours of the
  world file.

Each body is one :class:`SceneBody` (its objects, static placements and moving frames), so a
body that the World announces later (:mod:`bt_manip.sim.events`) is drawn with
:meth:`Scene.add_body` and taken away with :meth:`Scene.remove_body`, from the same visual
shapes (primitives and meshes) as the bodies of the world file.

The live viewer sends the objects once and then, after each tick, the poses of
:attr:`Scene.tracks` read by :meth:`Scene.read_poses`; the replay recorder embeds the same
objects (each mesh file once) and samples the same poses. Reading poses never changes the
simulation: it evaluates forward kinematics of the current joint state (the tests check that a
run gives bit-identical states with and without a viewer).
"""

from __future__ import annotations

import uuid
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pybullet as pb

from bt_manip.geometry import inverse_matrix, matrix_row, pose_matrix, row_matrix
from bt_manip.sim import pybullet_queries as pbq
from bt_manip.sim.compose import composed_urdf
from bt_manip.viz.urdf_visuals import Visual, read_visuals

ROOT = "/meshcat/bt_manip"
"""Scene path under which every bt-manip body is drawn."""

DEFAULT_RGBA = (0.7, 0.7, 0.72, 1.0)
MESH_FORMATS = {".dae": "dae", ".stl": "stl", ".obj": "obj"}
_X_TO_Z = np.array([[1.0, 0, 0, 0], [0, 0, -1.0, 0], [0, 1.0, 0, 0], [0, 0, 0, 1.0]])
"""Turns three.js cylinders (axis along y) into URDF/PyBullet ones (axis along z)."""


@dataclass
class SceneObject:
    """One drawable: a three.js object JSON at ``path``.

    Mesh data is not inside ``json``; ``mesh`` names the file and :meth:`Scene.lowered` or the
    replay page puts the content in. ``rgba`` is the colour the object is drawn with (None
    when the mesh file's own colours are used).
    """

    path: str
    json: dict[str, Any]
    body: str
    rgba: tuple[float, float, float, float] | None
    mesh: Path | None = None
    mesh_format: str = ""


@dataclass
class _BodyFrames:
    """How to read the frames of one moving body from PyBullet."""

    body_id: int
    base_offset: np.ndarray  # URDF root frame in the base centre-of-mass frame (4x4)
    link_ids: list[int]
    link_offsets: list[np.ndarray | None] = field(default_factory=list)
    """Per entry of ``link_ids``: the drawn link's frame in that PyBullet link's frame, for a
    link merged into another (:mod:`bt_manip.sim.fixed_links`); None for the link itself."""


@dataclass
class SceneBody:
    """The drawing of one body: node ``path``, its objects, and where it is placed.

    A fixed body has only :attr:`static` placements; a moving one has :attr:`tracks` (its own
    frame first, then its drawn links relative to it) read by :meth:`read_poses`.
    """

    name: str
    path: str
    objects: list[SceneObject] = field(default_factory=list)
    static: list[tuple[str, np.ndarray]] = field(default_factory=list)
    tracks: list[str] = field(default_factory=list)
    frames: _BodyFrames | None = None

    def read_poses(self, client: int) -> np.ndarray:
        """Current pose of every track: rows (x, y, z, qx, qy, qz, qw).

        The body's track is its URDF root frame in the world; a link's track is the link frame
        relative to the body's track.
        """
        out = np.empty((len(self.tracks), 7))
        body = self.frames
        if body is None:
            return out
        pos, quat = pb.getBasePositionAndOrientation(body.body_id, physicsClientId=client)
        base = pose_matrix(pos, quat) @ body.base_offset
        out[0] = matrix_row(base)
        if body.link_ids:
            carriers = sorted({j for j in body.link_ids if j >= 0})
            read = pbq.link_states(client, body.body_id, carriers)
            states = dict(zip(carriers, read, strict=True))
            inv = inverse_matrix(base)
            offsets = body.link_offsets or [None] * len(body.link_ids)
            for k, (j, offset) in enumerate(zip(body.link_ids, offsets, strict=True)):
                if j == -1:
                    link = base
                else:
                    state = states[j]
                    link = pose_matrix(state.frame_position, state.frame_orientation)
                out[1 + k] = matrix_row(inv @ (link if offset is None else link @ offset))
        return out


@dataclass
class Scene:
    """The drawable bodies of a world, by name, in the order they were added."""

    client: int = -1
    bodies: dict[str, SceneBody] = field(default_factory=dict)

    @property
    def objects(self) -> list[SceneObject]:
        """Every drawable of every body."""
        return [o for body in self.bodies.values() for o in body.objects]

    @property
    def static(self) -> list[tuple[str, np.ndarray]]:
        """Paths placed once (walls, furniture, link frames of fixed bodies)."""
        return [p for body in self.bodies.values() for p in body.static]

    @property
    def tracks(self) -> list[str]:
        """Paths whose pose changes; :meth:`read_poses` returns one row per track."""
        return [t for body in self.bodies.values() for t in body.tracks]

    @property
    def body_objects(self) -> dict[str, list[int]]:
        """Indices into :attr:`objects` by body name (to highlight a held object)."""
        out: dict[str, list[int]] = {}
        k = 0
        for name, body in self.bodies.items():
            out[name] = list(range(k, k + len(body.objects)))
            k += len(body.objects)
        return out

    def read_poses(self) -> np.ndarray:
        """Current pose of every track (see :meth:`SceneBody.read_poses`), bodies in order."""
        rows = [b.read_poses(self.client) for b in self.bodies.values() if b.tracks]
        return np.concatenate(rows) if rows else np.empty((0, 7))

    def add_body(self, world: Any, info: Any, path: str | None = None) -> SceneBody:
        """Draw one body of ``world`` at node ``path`` (default ``ROOT/<name>``): ``info`` has
        ``name``, ``body_id``, ``kind`` and ``spec`` (a World's BodyInfo, or the BodyAdded
        event announcing the body)."""
        urdf = _urdf_of(info, world)
        movable = info.kind in ("robot", "object")
        body = SceneBody(info.name, path or f"{ROOT}/{info.name}")
        if urdf is not None:
            scale = float(getattr(info.spec, "scale", 1.0) or 1.0)
            merged = world.robots[info.name].merged_frames if info.kind == "robot" else {}
            _add_urdf_body(body, self.client, info.body_id, urdf, scale, movable, merged)
        else:
            _add_primitive_body(body, self.client, info, movable)
        self.bodies[info.name] = body
        return body

    def remove_body(self, name: str) -> SceneBody | None:
        """Forget a body that left the world; returns its drawing (None if it had none)."""
        return self.bodies.pop(name, None)

    def mesh_files(self) -> list[Path]:
        """Every mesh file the scene uses, each once, in first-use order."""
        return mesh_files(self.objects)

    def lowered(self, obj: SceneObject, mesh_data: dict[Path, bytes]) -> dict[str, Any]:
        """The object JSON with its mesh content filled in, ready for msgpack."""
        return lowered(obj, mesh_data)


def mesh_files(objects: list[SceneObject]) -> list[Path]:
    """Every mesh file of ``objects``, each once, in first-use order."""
    seen: dict[Path, None] = {}
    for obj in objects:
        if obj.mesh is not None:
            seen.setdefault(obj.mesh, None)
    return list(seen)


def lowered(obj: SceneObject, mesh_data: dict[Path, bytes]) -> dict[str, Any]:
    """The object JSON with its mesh content filled in, ready for msgpack."""
    import umsgpack

    if obj.mesh is None:
        return obj.json
    data = mesh_data[obj.mesh]
    content: Any = umsgpack.Ext(0x12, data) if obj.mesh_format == "stl" else data.decode()
    json = dict(obj.json)
    if json["object"]["type"] == "_meshfile_object":
        json["object"] = {**json["object"], "data": content}
    else:
        json["geometries"] = [{**json["geometries"][0], "data": content}]
    return json


def colour_int(rgba: tuple[float, ...]) -> int:
    """0xRRGGBB of an RGBA colour in 0..1."""
    r, g, b = (max(0, min(255, round(v * 255))) for v in rgba[:3])
    return (r << 16) | (g << 8) | b


def column_major(t: np.ndarray) -> list[float]:
    """A 4x4 matrix as three.js and meshcat expect it (column-major)."""
    return [float(v) for v in np.asarray(t).T.flatten()]


def _material(rgba: tuple[float, ...]) -> dict[str, Any]:
    return {
        "uuid": str(uuid.uuid4()),
        "type": "MeshPhongMaterial",
        "color": colour_int(rgba),
        "reflectivity": 0.5,
        "side": 2,
        "transparent": bool(rgba[3] < 1.0),
        "opacity": float(rgba[3]),
    }


def primitive_json(
    kind: str, size: tuple[float, ...], rgba: tuple[float, ...], matrix: np.ndarray
) -> dict[str, Any]:
    """A three.js object JSON for a box (full extents), cylinder (radius, length, axis z) or
    sphere (radius), placed by ``matrix`` in its node."""
    geom: dict[str, Any] = {"uuid": str(uuid.uuid4())}
    if kind == "box":
        geom.update(type="BoxGeometry", width=size[0], height=size[1], depth=size[2])
    elif kind == "cylinder":
        geom.update(
            type="CylinderGeometry",
            radiusTop=size[0],
            radiusBottom=size[0],
            height=size[1],
            radialSegments=32,
        )
        matrix = matrix @ _X_TO_Z
    else:
        geom.update(type="SphereGeometry", radius=size[0], widthSegments=20, heightSegments=16)
    material = _material(rgba)
    return _mesh_object(geom, material, matrix)


def _mesh_object(
    geom: dict[str, Any], material: dict[str, Any], matrix: np.ndarray
) -> dict[str, Any]:
    """A meshcat scene object: one geometry with one material at ``matrix``."""
    return {
        "metadata": {"version": 4.5, "type": "Object"},
        "geometries": [geom],
        "materials": [material],
        "object": {
            "uuid": str(uuid.uuid4()),
            "type": "Mesh",
            "geometry": geom["uuid"],
            "material": material["uuid"],
            "matrix": column_major(matrix),
        },
    }


def _mesh_json(fmt: str, rgba: tuple[float, ...] | None, matrix: np.ndarray) -> dict[str, Any]:
    if rgba is None and fmt in ("dae", "obj"):
        # the mesh file's own materials
        return {
            "metadata": {"version": 4.5, "type": "Object"},
            "geometries": [],
            "materials": [],
            "object": {
                "uuid": str(uuid.uuid4()),
                "type": "_meshfile_object",
                "format": fmt,
                "resources": {},
                "matrix": column_major(matrix),
            },
        }
    geom = {"uuid": str(uuid.uuid4()), "type": "_meshfile_geometry", "format": fmt}
    material = _material(rgba or DEFAULT_RGBA)
    return _mesh_object(geom, material, matrix)


def _visual_object(path: str, body: str, visual: Visual, scale: float) -> SceneObject | None:
    origin = visual.origin.copy()
    origin[:3, 3] *= scale
    if visual.kind == "mesh":
        assert visual.mesh is not None
        fmt = MESH_FORMATS.get(visual.mesh.suffix.lower())
        if fmt is None:
            return None
        matrix = origin @ np.diag([*(s * scale for s in visual.scale), 1.0])
        return SceneObject(
            path, _mesh_json(fmt, visual.rgba, matrix), body, visual.rgba, visual.mesh, fmt
        )
    size = tuple(v * scale for v in visual.size)
    rgba = visual.rgba or DEFAULT_RGBA
    return SceneObject(path, primitive_json(visual.kind, size, rgba, origin), body, rgba)


def build_scene(world: Any) -> Scene:
    """The scene of a loaded world as it is now (see the module docstring)."""
    scene = Scene(client=world.client)
    for info in world.infos.values():
        if info.kind != "ground":
            scene.add_body(world, info)
    return scene


def _urdf_of(info: Any, world: Any) -> Path | None:
    if info.kind == "robot":
        robot = world.robots[info.name]
        return Path(composed_urdf(robot.description))
    urdf = getattr(info.spec, "urdf", None)
    return Path(urdf) if urdf is not None else None


def _add_urdf_body(
    body: SceneBody,
    c: int,
    body_id: int,
    urdf: Path,
    scale: float,
    movable: bool,
    merged: dict[str, Any] | None = None,
) -> None:
    """``merged``: a robot's :attr:`~bt_manip.sim.robot.Robot.merged_frames`; a merged link
    keeps its own node, placed at its carrier's frame times its offset."""
    links = {pbq.root_link_name(c, body_id): -1}
    for joint in pbq.joint_infos(c, body_id):
        links[joint.link_name] = joint.index
    offsets: dict[str, np.ndarray] = {}
    for name, (carrier, frame) in (merged or {}).items():
        links[name] = carrier
        offsets[name] = frame.matrix()
    dyn = pbq.dynamics_info(c, body_id, -1)
    inertial = pose_matrix(dyn.local_inertial_position, dyn.local_inertial_orientation)
    base_offset = inverse_matrix(inertial)
    visuals = [v for v in read_visuals(urdf) if v.link in links]
    order = {name: k for k, name in enumerate(links)}
    drawn = sorted(
        {v.link for v in visuals if links[v.link] >= 0 or v.link in offsets},
        key=lambda n: (links[n], order[n]),
    )
    counts: dict[str, int] = {}
    for visual in visuals:
        k = counts.get(visual.link, 0)
        counts[visual.link] = k + 1
        obj = _visual_object(f"{body.path}/{visual.link}/v{k}", body.name, visual, scale)
        if obj is not None:
            body.objects.append(obj)
    body.frames = _BodyFrames(
        body_id, base_offset, [links[n] for n in drawn], [offsets.get(n) for n in drawn]
    )
    body.tracks = [body.path] + [f"{body.path}/{n}" for n in drawn]
    if not movable:
        # fixed bodies: read once, then place statically
        rows = body.read_poses(c)
        body.static = [(p, row_matrix(r)) for p, r in zip(body.tracks, rows, strict=True)]
        body.tracks = []
        body.frames = None


def _add_primitive_body(body: SceneBody, c: int, info: Any, movable: bool) -> None:
    spec = info.spec
    parts = list(getattr(spec, "parts", None) or [])
    default_rgba = tuple(getattr(spec, "colour", None) or DEFAULT_RGBA)
    shapes = pbq.visual_shapes(c, info.body_id)
    for k, shape in enumerate(s for s in shapes if s.link == -1):
        geom_type, dims = shape.geometry_type, shape.dimensions
        local = pose_matrix(shape.local_position, shape.local_orientation)
        part_rgba = parts[k].colour if k < len(parts) and parts[k].colour else None
        rgba = tuple(part_rgba or default_rgba)
        size: tuple[float, ...]
        if geom_type == pb.GEOM_BOX:
            kind, size = "box", (dims[0], dims[1], dims[2])
        elif geom_type == pb.GEOM_CYLINDER:
            kind, size = "cylinder", (dims[1], dims[0])
        elif geom_type == pb.GEOM_SPHERE:
            kind, size = "sphere", (dims[0],)
        else:
            continue
        body.objects.append(
            SceneObject(
                f"{body.path}/v{k}", primitive_json(kind, size, rgba, local), info.name, rgba
            )  # type: ignore[arg-type]
        )
    if movable:
        body.frames = _BodyFrames(info.body_id, np.eye(4), [])
        body.tracks = [body.path]
    else:
        pos, quat = pb.getBasePositionAndOrientation(info.body_id, physicsClientId=c)
        body.static = [(body.path, pose_matrix(pos, quat))]
