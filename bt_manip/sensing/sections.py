"""Cross-sections of collision shapes by a horizontal plane.

A 2D laser sees the world where its scan plane cuts it. Each convex collision shape of
PyBullet cut by a horizontal plane ``z = h`` gives a convex polygon, a circle, or nothing:

- box, mesh (PyBullet keeps a mesh's convex hull, grown by :data:`MESH_MARGIN`), tilted
  cylinder: the solid is the convex
  hull of its corners, and its section is the 2D convex hull of the points where the hull's
  edges cross the plane (and of its corners on the plane). Exact for boxes and meshes; a
  cylinder's rims are polygons of :data:`RIM_POINTS` corners circumscribing the circle
  (within 0.1 mm of it for a 20 cm radius).
- sphere: the circle of radius ``sqrt(r^2 - d^2)``; upright cylinder: its circle; upright
  capsule: the circle at that height. A tilted capsule is the hull of points on its two end
  spheres (a close polygon).
- planes (the floor) and shapes the plane misses: nothing.

Sections are given in a frame whose z axis is the world's (a *planar frame*: the shape's
frame with only its heading kept, see :func:`planar_split`), so a body that moves in the plane
keeps its section, moved rigidly.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import pybullet as pb
from scipy.spatial import ConvexHull, QhullError

from bt_manip.cache import Memo, bytes_key
from bt_manip.navigation.shapes import convex_hull

__all__ = [
    "RIM_POINTS",
    "Section",
    "convex_section",
    "hull_edges",
    "planar_split",
    "shape_section",
]

RIM_POINTS = 72
"""Corners of the polygon standing for a cylinder's rim (it circumscribes the circle)."""
_BOX_SIGNS = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)],
                      dtype=float)
_BOX_EDGES = np.array([(i, i ^ bit) for i in range(8) for bit in (1, 2, 4) if (i ^ bit) > i])
MESH_MARGIN = 0.001
"""m: PyBullet's collision margin around a URDF's mesh (a convex hull, cylinders included): its
surface, for contacts and ray tests, lies this far out of the hull."""
MAX_VERTICES = 20_000
"""Largest vertex count of a mesh that is cut (a bigger one is cut as its first so many)."""


@dataclass(frozen=True)
class Section:
    """What a plane cuts out of some shapes: convex polygons ((n, 2) counter-clockwise vertex
    arrays) and circles ((cx, cy, r) rows of an (m, 3) array)."""

    polygons: tuple[np.ndarray, ...] = ()
    circles: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))

    def moved(self, x: float, y: float, yaw: float) -> Section:
        """The section turned by ``yaw`` and moved by (x, y)."""
        c, s = math.cos(yaw), math.sin(yaw)
        rot = np.array([[c, s], [-s, c]])  # row vectors: p @ rot = R p
        shift = np.array([x, y])
        polygons = tuple(p @ rot + shift for p in self.polygons)
        circles = self.circles.copy()
        if len(circles):
            circles[:, :2] = circles[:, :2] @ rot + shift
        return Section(polygons, circles)

    @staticmethod
    def join(parts: list[Section]) -> Section:
        polygons = tuple(p for part in parts for p in part.polygons)
        circles = [part.circles for part in parts if len(part.circles)]
        return Section(polygons, np.concatenate(circles) if circles else np.zeros((0, 3)))


def planar_split(position: np.ndarray, rotation: np.ndarray) -> tuple[float, float, float,
                                                                        np.ndarray, np.ndarray]:
    """A pose split into its planar part (x, y, heading) and the rest: the pose in the frame
    at (x, y, 0) turned by the heading. The heading is that of the pose's x axis (of its y axis
    when x points straight up or down)."""
    r = rotation
    if math.hypot(r[0, 0], r[1, 0]) > 1e-6:
        yaw = math.atan2(r[1, 0], r[0, 0])
    else:
        yaw = math.atan2(-r[0, 1], r[1, 1])
    c, s = math.cos(yaw), math.sin(yaw)
    back = np.array([[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]])
    local_p = np.array([0.0, 0.0, position[2]])
    return float(position[0]), float(position[1]), yaw, local_p, back @ r


def convex_section(points: np.ndarray, edges: np.ndarray, height: float) -> np.ndarray | None:
    """The section by ``z = height`` of the convex hull of ``points`` (n, 3) whose edges are
    ``edges`` (k, 2 indices): a counter-clockwise polygon (m, 2), or None when the plane misses
    it or cuts only a point or a line."""
    z = points[:, 2] - height
    if z.max() < 0.0 or z.min() > 0.0:
        return None
    za, zb = z[edges[:, 0]], z[edges[:, 1]]
    crossing = (za * zb) < 0.0
    a = points[edges[crossing, 0]]
    b = points[edges[crossing, 1]]
    t = (za[crossing] / (za[crossing] - zb[crossing]))[:, None]
    cut = a[:, :2] + t * (b[:, :2] - a[:, :2])
    on = points[z == 0.0, :2]
    pts = np.concatenate([cut, on]) if len(on) else cut
    if len(pts) < 3:
        return None
    hull = convex_hull(pts)
    return hull if len(hull) >= 3 else None


_HULLS: Memo[np.ndarray] = Memo(256)
"""Edges of the convex hulls of mesh vertices, by the vertices' bytes."""


def hull_edges(points: np.ndarray) -> np.ndarray:
    """The edges (k, 2 indices into ``points``) of the 3D convex hull of ``points``; every
    pair of points for a degenerate (flat) set. Remembered per vertex set."""
    key = bytes_key(points.tobytes())
    known = _HULLS.get(key)
    if known is not None:
        return known
    try:
        simplices = ConvexHull(points).simplices
        pairs = np.concatenate([simplices[:, [0, 1]], simplices[:, [1, 2]],
                                simplices[:, [2, 0]]])
        edges = np.unique(np.sort(pairs, axis=1), axis=0)
    except (QhullError, ValueError):
        n = min(len(points), 64)
        edges = np.array([(i, j) for i in range(n) for j in range(i + 1, n)], dtype=int)
        edges = edges.reshape(-1, 2)
    out = np.asarray(edges, dtype=np.int64)
    _HULLS.put(key, out)
    return out


def _frame_points(local: np.ndarray, position: np.ndarray, rotation: np.ndarray) -> np.ndarray:
    return np.asarray(position + local @ rotation.T)


def _rim_points(length: float, radius: float) -> np.ndarray:
    """Corners of a cylinder along z: two rims of :data:`RIM_POINTS`, circumscribing."""
    a = np.arange(RIM_POINTS) * (2.0 * math.pi / RIM_POINTS)
    r = radius / math.cos(math.pi / RIM_POINTS)
    ring = np.column_stack([r * np.cos(a), r * np.sin(a)])
    half = length / 2.0
    return np.concatenate([np.column_stack([ring, np.full(RIM_POINTS, -half)]),
                           np.column_stack([ring, np.full(RIM_POINTS, half)])])


def _rim_edges() -> np.ndarray:
    n = RIM_POINTS
    i = np.arange(n)
    return np.concatenate([np.column_stack([i, (i + 1) % n]),
                           np.column_stack([n + i, n + (i + 1) % n]),
                           np.column_stack([i, n + i])])


_RIM_EDGES = _rim_edges()


def _capsule_points(length: float, radius: float) -> np.ndarray:
    """Points on the two end spheres of a capsule along z (a close polyhedron around it)."""
    lat = np.linspace(-math.pi / 2, math.pi / 2, 13)
    lon = np.arange(24) * (2.0 * math.pi / 24)
    la, lo = np.meshgrid(lat, lon)
    r = radius / math.cos(math.pi / 24)
    sphere = np.column_stack([(r * np.cos(la) * np.cos(lo)).ravel(),
                              (r * np.cos(la) * np.sin(lo)).ravel(), (r * np.sin(la)).ravel()])
    half = np.array([0.0, 0.0, length / 2.0])
    return np.concatenate([sphere + half, sphere - half])


def shape_section(
    geometry: int,
    dimensions: tuple[float, ...],
    position: np.ndarray,
    rotation: np.ndarray,
    height: float,
    vertices: np.ndarray | None = None,
) -> Section:
    """The section by ``z = height`` of one collision shape whose frame is (``position``,
    ``rotation``) in a frame with a vertical z axis; ``vertices`` are a mesh's, in the shape's
    frame (see :func:`bt_manip.sim.pybullet_queries.mesh_vertices`, whose frame is the link's:
    pass the link's frame then)."""
    if geometry == pb.GEOM_BOX:
        half = np.asarray(dimensions[:3], dtype=float) / 2.0
        pts = _frame_points(_BOX_SIGNS * half, position, rotation)
        return _polygon(convex_section(pts, _BOX_EDGES, height))
    if geometry == pb.GEOM_SPHERE:
        r, d = float(dimensions[0]), abs(float(position[2]) - height)
        if d > r:
            return Section()
        return _circle(position, math.sqrt(r * r - d * d))
    if geometry in (pb.GEOM_CYLINDER, pb.GEOM_CAPSULE):
        length, radius = float(dimensions[0]), float(dimensions[1])
        capsule = geometry == pb.GEOM_CAPSULE
        axis = rotation[:, 2]
        if abs(axis[2]) > 1.0 - 1e-12:  # upright: a circle
            d = abs(height - float(position[2]))
            if d <= length / 2.0:
                return _circle(position, radius)
            if capsule and d <= length / 2.0 + radius:
                e = d - length / 2.0
                return _circle(position, math.sqrt(radius * radius - e * e))
            return Section()
        if capsule:
            local = _capsule_points(length, radius)
            pts = _frame_points(local, position, rotation)
            return _polygon(convex_section(pts, hull_edges(local), height))
        pts = _frame_points(_rim_points(length, radius), position, rotation)
        return _polygon(convex_section(pts, _RIM_EDGES, height))
    if geometry == pb.GEOM_MESH and vertices is not None and len(vertices):
        local = vertices[:MAX_VERTICES]
        pts = _frame_points(local, position, rotation)
        z = pts[:, 2]
        if z.max() < height or z.min() > height:
            return Section()
        return _polygon(_offset(convex_section(pts, hull_edges(local), height), MESH_MARGIN))
    return Section()  # planes, and shapes without vertices


def _offset(poly: np.ndarray | None, margin: float) -> np.ndarray | None:
    """A counter-clockwise convex polygon with every edge moved ``margin`` outwards."""
    if poly is None:
        return None
    edge = np.roll(poly, -1, axis=0) - poly
    normal = np.column_stack([edge[:, 1], -edge[:, 0]])
    normal /= np.linalg.norm(normal, axis=1)[:, None]
    before = np.roll(normal, 1, axis=0)  # the normal of the edge ending at each vertex
    bisector = before + normal
    scale = margin / (1.0 + np.sum(before * normal, axis=1))
    return np.asarray(poly + bisector * scale[:, None])


def _polygon(poly: np.ndarray | None) -> Section:
    return Section() if poly is None else Section((poly,))


def _circle(position: np.ndarray, radius: float) -> Section:
    if radius <= 0.0:
        return Section()
    return Section((), np.array([[float(position[0]), float(position[1]), radius]]))
