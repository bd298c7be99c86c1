"""The robot file PyBullet loads when it draws nothing: no visuals, collision meshes as hulls,
fixed links merged.

A composed robot URDF (:mod:`bt_manip.sim.compose`) names visual meshes (COLLADA files of
hundreds of kilobytes) and collision meshes (STL files of thousands of triangles). Headless,
PyBullet never draws the visuals, yet parsing them is most of the time ``loadURDF`` takes; and of
each STL collision mesh PyBullet keeps only the convex hull of its vertices, which it computes
again at every load. :func:`physics_urdf` therefore writes, once, a variant of the file:

- every ``<visual>`` element removed (the live viewer and the replay page read the visuals from
  the composed file, not from PyBullet);
- every STL collision mesh replaced by an STL holding only its convex hull, whose vertices are
  vertices of the original (the same float32 values), so PyBullet builds the same convex shape
  from far fewer points (a ``<collision concave="yes">`` keeps its mesh: PyBullet keeps its
  triangles).

- every child of a fixed joint folded into its parent (:mod:`bt_manip.sim.fixed_links`): the
  same rigid assembly with fewer PyBullet links, which makes each physics step cheaper. The
  merged links' frames are kept beside the file (:class:`PhysicsModel`), so
  :class:`~bt_manip.sim.robot.Robot` still gives the pose of every URDF link by name.

Movable joints, masses, inertia, collision shapes and contact parameters are those of the
composed file. A mesh whose hull cannot be computed (flat or degenerate) is kept as it is. The
files are written under the URDF cache folder (``physics/`` and ``hulls/``), keyed by a hash of
the URDF text and of each mesh's path, size and modification time; writes are atomic.

PyBullet's own window (``World(gui=True)``) loads the composed file with its visuals.
"""

from __future__ import annotations

import hashlib
import json
import struct
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from pathlib import Path

import defusedxml.ElementTree as SafeET
import numpy as np

from bt_manip.input_files import read_bounded
from bt_manip.sim.compose import MAX_URDF_BYTES, cache_dir, file_stamp, write_atomic_bytes
from bt_manip.sim.fixed_links import MergedFrame, merge_fixed_links
from bt_manip.sim.mesh_check import MAX_MESH_BYTES

PHYSICS_VERSION = 3
"""Bumped whenever the output for the same inputs changes."""


@dataclass(frozen=True)
class PhysicsModel:
    """The file PyBullet loads and the frames of the links merged into others (by URDF link
    name; empty when nothing was merged)."""

    path: Path
    merged: dict[str, MergedFrame] = field(default_factory=dict)


def physics_urdf(urdf: Path) -> Path:
    """Path of :func:`physics_model`'s file."""
    return physics_model(urdf).path


def physics_model(urdf: Path) -> PhysicsModel:
    """The variant of ``urdf`` (a composed or plain robot URDF with absolute mesh paths) that
    PyBullet loads headless, see the module docstring; ``urdf`` itself when it names no mesh
    and has no fixed joint."""
    data = read_bounded(urdf, MAX_URDF_BYTES, "URDF file")
    if b"<mesh" not in data and b'"fixed"' not in data and b"'fixed'" not in data:
        return PhysicsModel(urdf)
    root: ET.Element = SafeET.fromstring(data)
    meshes = [m for m in root.iter("mesh") if m.get("filename")]
    digest = hashlib.sha256(f"physics-{PHYSICS_VERSION}".encode())
    digest.update(data)
    for mesh in meshes:
        digest.update(_file_stamp(Path(mesh.get("filename", ""))))
    target = cache_dir() / "physics" / f"{urdf.stem}-{digest.hexdigest()[:16]}.urdf"
    frames_file = target.with_suffix(".frames.json")
    if target.is_file() and frames_file.is_file():
        try:
            return PhysicsModel(target, _read_frames(frames_file))
        except (OSError, ValueError, KeyError, TypeError):
            pass  # written by something else: write it again
    for link in root.iter("link"):
        for visual in link.findall("visual"):
            link.remove(visual)
        for collision in link.findall("collision"):
            if collision.get("concave", "").lower() in ("yes", "true", "1"):
                continue  # PyBullet keeps such a mesh's triangles, not its hull
            for mesh in collision.iter("mesh"):
                source = Path(mesh.get("filename", ""))
                if source.suffix.lower() == ".stl":
                    mesh.set("filename", str(hull_stl(source)))
    merged = merge_fixed_links(root)
    ET.indent(root, space="  ")
    text = '<?xml version="1.0"?>\n' + ET.tostring(root, encoding="unicode") + "\n"
    frames = {
        name: {"carrier": f.carrier, "position": list(f.position), "quat": list(f.quat)}
        for name, f in merged.items()
    }
    write_atomic_bytes(frames_file, json.dumps(frames, indent=1).encode())
    write_atomic_bytes(target, text.encode())
    return PhysicsModel(target, merged)


def _read_frames(path: Path) -> dict[str, MergedFrame]:
    raw = json.loads(path.read_text())
    return {
        str(name): MergedFrame(
            str(f["carrier"]),
            tuple(float(v) for v in f["position"]),  # type: ignore[arg-type]
            tuple(float(v) for v in f["quat"]),  # type: ignore[arg-type]
        )
        for name, f in raw.items()
    }


def hull_stl(source: Path) -> Path:
    """An STL file holding the convex hull of the STL mesh ``source`` (cached); ``source`` itself
    when the hull cannot be computed (fewer than four points, all in one plane) or the file
    cannot be read as an STL."""
    stamp = hashlib.sha256(f"hull-{PHYSICS_VERSION}".encode() + _file_stamp(source))
    target = cache_dir() / "hulls" / f"{source.stem}-{stamp.hexdigest()[:16]}.stl"
    if target.is_file():
        return target
    try:
        vertices = read_stl_vertices(source)
    except (OSError, ValueError):
        return source
    triangles = hull_triangles(vertices)
    if triangles is None:
        return source
    write_atomic_bytes(target, stl_bytes(triangles))
    return target


def read_stl_vertices(path: Path) -> np.ndarray:
    """The vertices of an STL file (binary or ASCII) as an (n, 3) float32 array, duplicates
    included; ValueError when the file holds no triangle or is larger than the mesh limit."""
    if path.stat().st_size > MAX_MESH_BYTES:
        raise ValueError(f"{path} is larger than the mesh limit")
    data = path.read_bytes()
    if len(data) >= 84:
        (count,) = struct.unpack_from("<I", data, 80)
        if count > 0 and len(data) == 84 + 50 * count:
            records = np.frombuffer(data, dtype=_BINARY_TRIANGLE, count=count, offset=84)
            return np.ascontiguousarray(records["vertices"].reshape(-1, 3))
    values: list[float] = []
    for line in data.decode("ascii", errors="replace").splitlines():
        parts = line.split()
        if len(parts) == 4 and parts[0] == "vertex":
            values.extend(float(p) for p in parts[1:])
    if not values:
        raise ValueError(f"{path} holds no triangle")
    return np.asarray(values, dtype=np.float32).reshape(-1, 3)


def hull_triangles(vertices: np.ndarray) -> np.ndarray | None:
    """Triangles (m, 3, 3) whose vertices are the inputs on or near the convex hull of
    ``vertices``, each point once (the last triangle repeats a point to fill it); None when
    the points span no volume.

    Qhull merges facets that are nearly coplanar and drops their vertices (by micrometres),
    where PyBullet's own hull may keep them; so every input point closer to the hull's surface
    than :data:`NEAR_SURFACE` of the mesh's extent is kept too (as a degenerate triangle), and
    PyBullet builds its hull from a set holding all of its own vertices.
    """
    from scipy.spatial import ConvexHull, QhullError

    points = np.unique(vertices, axis=0)
    if len(points) < 4:
        return None
    try:
        hull = ConvexHull(points.astype(np.float64))
    except (QhullError, ValueError):
        return None
    extent = float(np.ptp(points, axis=0).max())
    depth = -(hull.equations[:, :3] @ points.T.astype(np.float64)
              + hull.equations[:, 3:4]).max(axis=0)
    keep = depth <= NEAR_SURFACE * extent
    keep[hull.vertices] = True
    # the kept points, each once, in the order they first come in the original vertex stream
    # (PyBullet's hull of a point set does not depend on repeats; each repeat costs it time)
    _, first, index = np.unique(vertices, axis=0, return_index=True, return_inverse=True)
    order = np.sort(first)
    stream = vertices[order[keep[index.ravel()][order]]]
    pad = (-len(stream)) % 3
    stream = np.concatenate([stream, np.repeat(stream[-1:], pad, axis=0)])
    return np.asarray(stream.reshape(-1, 3, 3), dtype=np.float32)


NEAR_SURFACE = 1e-3
"""Points this close to the hull's surface, relative to the mesh's extent, are kept."""


def stl_bytes(triangles: np.ndarray) -> bytes:
    """A binary STL of ``triangles`` (m, 3, 3); normals are left zero (PyBullet ignores them)."""
    records = np.zeros(len(triangles), dtype=_BINARY_TRIANGLE)
    records["vertices"] = triangles.reshape(-1, 9)
    header = b"bt-manip convex hull".ljust(80, b" ")
    return header + struct.pack("<I", len(triangles)) + records.tobytes()


_BINARY_TRIANGLE = np.dtype(
    [("normal", "<f4", 3), ("vertices", "<f4", 9), ("attribute", "<u2")]
)


def _file_stamp(path: Path) -> bytes:
    """The path, size, modification time and inode of a file (``None`` when missing), as the
    bytes a cache key is made of."""
    return f"{path}:{file_stamp(path)}".encode()
