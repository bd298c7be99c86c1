"""Planar outlines of PyBullet collision shapes, sliced to a height band.

Navigation works in the ground plane: every collision shape of a body that reaches into the
height band the robot sweeps is reduced to its outline seen from above, as a :class:`Disc` or a
convex :class:`Polygon`, in the world frame or in another frame (a robot's base, to build its
footprint).

- Boxes: the part of the box inside the band, exactly (the box is clipped by the two band
  planes, then projected).
- Spheres: the widest circle inside the band, exactly.
- Upright cylinders and capsules: their circle. Tilted ones: a polygon circumscribing the
  projection of the whole solid.
- Meshes: the projection of their collision vertices (``getMeshData``, convex hull); when
  PyBullet gives no vertices, the link's axis-aligned bounding box.
- Planes are ignored (the floor is not an obstacle); anything else uses its bounding box.

Collision frames are taken from ``getCollisionShapeData``, which reports them relative to the
link's centre-of-mass frame (``getBasePositionAndOrientation`` / ``getLinkState``).
"""

from __future__ import annotations

import bisect
import math
import struct
from collections.abc import Sequence
from dataclasses import dataclass, field

import numba
import numpy as np
import pybullet as pb

from bt_manip.cache import Memo
from bt_manip.geometry import Frame, compose, frame_of, inverse
from bt_manip.sim import pybullet_queries as pbq

ZBand = tuple[float, float]


@dataclass(frozen=True)
class Disc:
    """A filled circle in the plane."""

    cx: float
    cy: float
    radius: float

    def extent(self) -> tuple[float, float, float, float]:
        """(xmin, ymin, xmax, ymax)."""
        r = self.radius
        return self.cx - r, self.cy - r, self.cx + r, self.cy + r

    def points(self, n: int = 32) -> np.ndarray:
        """``n`` points on a polygon that circumscribes the circle."""
        a = np.arange(n) * (2.0 * math.pi / n)
        r = self.radius / math.cos(math.pi / n)
        return np.column_stack([self.cx + r * np.cos(a), self.cy + r * np.sin(a)])


@dataclass(frozen=True)
class Polygon:
    """A filled convex polygon in the plane; ``vertices`` (n, 2) counter-clockwise."""

    vertices: np.ndarray

    def extent(self) -> tuple[float, float, float, float]:
        lo = self.vertices.min(axis=0)
        hi = self.vertices.max(axis=0)
        return float(lo[0]), float(lo[1]), float(hi[0]), float(hi[1])

    def points(self, n: int = 0) -> np.ndarray:
        return self.vertices


Outline = Disc | Polygon


def convex_hull(points: np.ndarray) -> np.ndarray:
    """Counter-clockwise convex hull of 2-D points (monotone chain); collinear points dropped."""
    pts = _sorted_unique_rows(np.round(np.asarray(points, dtype=float), 12))
    if len(pts) <= 2:
        return pts
    return _monotone_chain(pts)


def _sorted_unique_rows(pts: np.ndarray) -> np.ndarray:
    """The distinct rows of an (n, 2) array sorted by x then y: ``np.unique(pts, axis=0)``,
    computed by a lexicographic sort and a comparison of neighbours (much cheaper). Arrays
    holding a zero (0.0 and -0.0 are equal, and which one ``np.unique`` keeps is its own
    choice) or a NaN go through ``np.unique`` itself."""
    if pts.ndim != 2 or pts.shape[1] != 2 or not np.all(pts != 0.0):  # also catches NaN
        return np.unique(pts, axis=0)
    s = pts[np.lexsort((pts[:, 1], pts[:, 0]))]
    keep = np.ones(len(s), dtype=bool)
    keep[1:] = (s[1:, 0] != s[:-1, 0]) | (s[1:, 1] != s[:-1, 1])
    return s[keep]


@numba.njit(cache=True)
def _monotone_chain(pts: np.ndarray) -> np.ndarray:  # pragma: no cover - compiled
    """Andrew's monotone chain over distinct points sorted by x then y (at least three): the
    lower chain left to right, then the upper chain right to left, each point kept while the
    chain turns left (a point on a straight stretch is dropped)."""
    n = pts.shape[0]
    chain = np.empty((2 * n, 2))
    k = 0
    for i in range(n):
        k = _chain_push(chain, k, 0, pts[i, 0], pts[i, 1])
    lower = k
    for i in range(n - 1, -1, -1):
        k = _chain_push(chain, k, lower, pts[i, 0], pts[i, 1])
    return np.concatenate((chain[: lower - 1], chain[lower : k - 1]))


@numba.njit(cache=True)
def _chain_push(
    chain: np.ndarray, k: int, start: int, px: float, py: float
) -> int:  # pragma: no cover - compiled
    """Add (px, py) to the chain of ``k`` points whose current part begins at ``start``, first
    dropping the points after which it would not turn left; the new length."""
    while k - start >= 2:
        ox, oy = chain[k - 2, 0], chain[k - 2, 1]
        ax, ay = chain[k - 1, 0], chain[k - 1, 1]
        if (ax - ox) * (py - oy) - (ay - oy) * (px - ox) > 0.0:
            break
        k -= 1
    chain[k, 0], chain[k, 1] = px, py
    return k + 1


def planar_frame(x: float, y: float, yaw: float) -> Frame:
    """The frame at (x, y, 0) turned by ``yaw`` about z."""
    c, s = math.cos(yaw), math.sin(yaw)
    return np.array([x, y, 0.0]), np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


_BOX_SIGNS = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)])
"""The eight corners of a box as signs of its half extents; corner ``i`` and ``i ^ bit``
(bit 1, 2 or 4) share an edge."""
_BOX_EDGES = [(i, i ^ bit) for i in range(8) for bit in (1, 2, 4) if (i ^ bit) > i]
_EDGE_A = np.array([i for i, _ in _BOX_EDGES])
_EDGE_B = np.array([j for _, j in _BOX_EDGES])


def _box_slice(frame: Frame, half: np.ndarray, band: ZBand) -> np.ndarray | None:
    """Plane points of the part of a box inside the z band (None if it misses the band): the
    corners inside it and where the edges cross its two planes."""
    corners = frame[0] + (_BOX_SIGNS * half) @ frame[1].T
    z = corners[:, 2]
    lo, hi = band
    if z.max() < lo or z.min() > hi:
        return None
    pts = [corners[(z >= lo) & (z <= hi), :2]]
    c = corners.tolist()  # plain floats: the same arithmetic, less overhead per corner
    crossings = []
    for i, j in _BOX_EDGES:
        xa, ya, za = c[i]
        xb, yb, zb = c[j]
        for plane in (lo, hi):
            if (za - plane) * (zb - plane) < 0.0:
                t = (plane - za) / (zb - za)
                crossings.append((xa + t * (xb - xa), ya + t * (yb - ya)))
    if crossings:
        pts.append(np.array(crossings, dtype=float))
    pts_all = np.concatenate(pts)
    return pts_all if len(pts_all) else None


def _sphere_slice(centre: np.ndarray, radius: float, band: ZBand) -> Disc | None:
    lo, hi = band
    cz = centre[2]
    if cz + radius < lo or cz - radius > hi:
        return None
    d = 0.0 if lo <= cz <= hi else min(abs(cz - lo), abs(cz - hi))
    r = math.sqrt(max(radius * radius - d * d, 0.0))
    return Disc(float(centre[0]), float(centre[1]), r)


def _round_solid_heights(
    frame: Frame, length: float, radius: float, capsule: bool
) -> tuple[float, float]:
    """The lowest and highest heights of a cylinder (or capsule) along the frame's z axis."""
    centre = frame[0]
    az = abs(float(frame[1][2, 2]))
    half_z = 0.5 * length * az + radius * (1.0 if capsule else math.sqrt(max(1.0 - az * az, 0.0)))
    return float(centre[2] - half_z), float(centre[2] + half_z)


def _round_solid_misses(
    frame: Frame, length: float, radius: float, capsule: bool, band: ZBand
) -> bool:
    """Whether a cylinder (or capsule) along the frame's z axis lies wholly below or above
    the band."""
    low, high = _round_solid_heights(frame, length, radius, capsule)
    return high < band[0] or low > band[1]


def _round_solid(
    frame: Frame, length: float, radius: float, capsule: bool, band: ZBand
) -> Outline | None:
    """Cylinder (or capsule) along the frame's z axis."""
    if _round_solid_misses(frame, length, radius, capsule, band):
        return None
    axis = frame[1][:, 2]
    centre = frame[0]
    az = abs(float(axis[2]))
    if az > 1.0 - 1e-9:
        return Disc(float(centre[0]), float(centre[1]), radius)
    ends = [centre + axis * (0.5 * length), centre - axis * (0.5 * length)]
    n = 24
    a = np.arange(n) * (2.0 * math.pi / n)
    r = radius / math.cos(math.pi / n)
    pts = []
    if capsule:  # each end sphere projects to a disc
        for e in ends:
            pts.append(np.column_stack([e[0] + r * np.cos(a), e[1] + r * np.sin(a)]))
    else:  # rims of the two end faces
        u = frame[1][:, 0]
        v = frame[1][:, 1]
        for e in ends:
            rim = e + r * (np.outer(np.cos(a), u) + np.outer(np.sin(a), v))
            pts.append(rim[:, :2])
    return Polygon(convex_hull(np.concatenate(pts)))


def link_frame(client: int, body: int, link: int) -> Frame:
    """World frame of a link's centre of mass (the frame collision shapes are given in)."""
    return frame_of(*pbq.com_pose(client, body, link))


def _aabb_outline(client: int, body: int, link: int, ref: Frame, band: ZBand) -> Outline | None:
    lo, hi = pbq.aabb(client, body, link)
    centre = (np.asarray(lo) + np.asarray(hi)) / 2.0
    half = (np.asarray(hi) - np.asarray(lo)) / 2.0
    return _points_outline(_box_slice(compose(ref, (centre, np.eye(3))), half, band))


def _points_outline(points: np.ndarray | None) -> Outline | None:
    if points is None or len(points) == 0:
        return None
    hull = convex_hull(points)
    if len(hull) < 3:  # degenerate (a sliver): widen it a little so it still rasterises
        lo = points.min(axis=0) - 1e-6
        hi = points.max(axis=0) + 1e-6
        hull = np.array([[lo[0], lo[1]], [hi[0], lo[1]], [hi[0], hi[1]], [lo[0], hi[1]]])
    return Polygon(hull)


def body_outlines(
    client: int,
    body: int,
    band: ZBand,
    reference: Frame | None = None,
    links: list[int] | None = None,
) -> list[Outline]:
    """Outlines of a body's collision shapes inside the z band, in ``reference`` coordinates.

    ``reference`` is the frame (position, rotation) the outlines are expressed in; the world
    frame if ``None``. ``band`` is measured along the reference frame's z axis. ``links``
    restricts the links looked at (all, base included, by default).

    Outlines are functions of numbers alone, so they are remembered for the process (walls,
    furniture and objects at rest are outlined again in every episode and height band):

    - per primitive shape (:data:`OUTLINE_MEMO`), under the bytes of every number its outline
      is computed from (type, size, frame, the link's pose, the reference frame, the band);
      meshes, mostly the links of a moving robot, are outlined every time;
    - per body made of boxes, cylinders and capsules (:data:`BODY_MEMO`), under the bytes of
      its shapes' numbers and the reference frame, and then per *band class*: where the band's
      two ends fall among the heights at which the outlines can change (see
      :class:`_BandLevels`). Bands that differ in the last bits (a robot's height on another
      start pose) fall in the same class and get the very same outlines.

    A remembered polygon's vertices are read-only.
    """
    ref_inv = inverse(reference) if reference is not None else (np.zeros(3), np.eye(3))
    ref_key = ref_inv[0].tobytes() + ref_inv[1].tobytes()
    if links is None:
        links = list(range(-1, pbq.joint_count(client, body)))
    items: list[_Item] = []
    for link in links:
        shapes = pbq.collision_shapes(client, body, link)
        if shapes:
            com_pose = pbq.com_pose(client, body, link)
            items += [(link, index, shape, com_pose) for index, shape in enumerate(shapes)]
    if not all(shape.geometry_type in _BANDED for _, _, shape, _ in items):
        return _outlines(client, body, items, ref_inv, ref_key, band)
    key = ref_key + b"".join(_shape_key(shape, com_pose) for _, _, shape, com_pose in items)
    levels = BODY_MEMO.get(key)
    if levels is None:
        levels = _BandLevels.of(items, ref_inv)
        BODY_MEMO.put(key, levels)
    cls = levels.band_class(band)
    if cls is None:
        return _outlines(client, body, items, ref_inv, ref_key, band)
    known = levels.outlines.get(cls)
    if known is None:
        known = tuple(_outlines(client, body, items, ref_inv, ref_key, band))
        for outline in known:
            if isinstance(outline, Polygon):
                outline.vertices.flags.writeable = False
        if len(levels.outlines) < _BandLevels.MAX_CLASSES:
            levels.outlines[cls] = known
    return list(known)


_Item = tuple[int, int, pbq.ShapeData, tuple[Sequence[float], Sequence[float]]]
"""A collision shape to outline: its link, its index in the link, its data, the link's
centre-of-mass pose."""


def _outlines(
    client: int, body: int, items: list[_Item], ref_inv: Frame, ref_key: bytes, band: ZBand
) -> list[Outline]:
    """The outlines of ``items`` (the collision shapes of ``body``), shape by shape, those
    outlined before with the same numbers taken from :data:`OUTLINE_MEMO`."""
    frame_key = ref_key + _BAND.pack(*band)
    out: list[Outline] = []
    coms: dict[int, Frame] = {}  # per link, computed when an outline is not remembered
    for link, index, shape, com_pose in items:
        geom = shape.geometry_type
        if geom == pb.GEOM_PLANE:
            continue
        key: bytes | None = None
        if geom in _PRIMITIVES:  # meshes: mostly a robot's links, never twice in one place
            key = _shape_key(shape, com_pose) + frame_key
        if key is not None:
            known = OUTLINE_MEMO.get(key)
            if known is not None:
                if known[0] is not None:
                    out.append(known[0])
                continue
        com = coms.get(link)
        if com is None:
            com = coms[link] = compose(ref_inv, frame_of(*com_pose))
        frame = compose(com, frame_of(shape.local_position, shape.local_orientation))
        outline = _shape_outline(client, body, link, index, shape, com, frame, ref_inv, band)
        if key is not None:
            if isinstance(outline, Polygon):
                outline.vertices.flags.writeable = False
            OUTLINE_MEMO.put(key, (outline,))
        if outline is not None:
            out.append(outline)
    return out


@dataclass
class _BandLevels:
    """The heights (in the reference frame) at which the outlines of a body of boxes,
    cylinders and capsules can change with the band, and the outlines per band class.

    - A box is sliced by comparing each corner's height with the band's ends (corners in the
      band) and each edge's ends with the band's planes (edges crossing a plane). When every
      edge that is not level is upright (its ends have the same x and y, bit for bit), the
      point where it crosses a plane is that x and y whatever the plane's height: the slice
      then depends on the band only through those comparisons, with the corners' heights.
    - A cylinder or capsule is outlined whole unless it lies wholly below or above the band:
      two comparisons, with its lowest and highest heights.

    The class of a band is where each of its ends falls among these heights (below, on,
    above each), so two bands of one class give the same outlines. ``levels`` is empty for a
    body that does not qualify (a tilted box): then there are no classes.
    """

    levels: list[float]
    outlines: dict[tuple[int, int, int, int], tuple[Outline, ...]] = field(default_factory=dict)

    MAX_CLASSES = 64
    """Band classes remembered per body at most."""

    @classmethod
    def of(cls, items: list[_Item], ref_inv: Frame) -> _BandLevels:
        levels: list[float] = []
        for _, _, shape, com_pose in items:
            geom, dims = shape.geometry_type, shape.dimensions
            if geom == pb.GEOM_PLANE:
                continue
            com = compose(ref_inv, frame_of(*com_pose))
            frame = compose(com, frame_of(shape.local_position, shape.local_orientation))
            if geom == pb.GEOM_BOX:
                corners = frame[0] + (_BOX_SIGNS * (np.asarray(dims) / 2.0)) @ frame[1].T
                a, b = corners[_EDGE_A], corners[_EDGE_B]
                sloped = a[:, 2] != b[:, 2]
                if not np.array_equal(a[sloped, :2], b[sloped, :2]):
                    return cls([])  # a tilted box: its slice moves with the band
                levels += corners[:, 2].tolist()
            else:  # cylinder or capsule
                low, high = _round_solid_heights(
                    frame, float(dims[0]), float(dims[1]), geom == pb.GEOM_CAPSULE
                )
                levels += [low, high]
        if not all(math.isfinite(v) for v in levels):
            return cls([])
        return cls(sorted(set(levels)) or [0.0])

    def band_class(self, band: ZBand) -> tuple[int, int, int, int] | None:
        """Where the band's ends fall among the levels; None when the body has no classes, or
        when an end is so close to a level (below 1e-150 m) that a product of two differences
        could round to zero."""
        if not self.levels:
            return None
        lo, hi = float(band[0]), float(band[1])
        if not (math.isfinite(lo) and math.isfinite(hi)):
            return None
        levels = self.levels
        ends = []
        for end in (lo, hi):
            first, last = bisect.bisect_left(levels, end), bisect.bisect_right(levels, end)
            for i in (first - 1, last):
                if 0 <= i < len(levels) and 0.0 < abs(levels[i] - end) < 1e-150:
                    return None
            ends += [first, last]
        return ends[0], ends[1], ends[2], ends[3]


BODY_MEMO: Memo[_BandLevels] = Memo(4096)
"""Per body (the bytes of its shapes' numbers and of the reference frame), the heights at
which its outlines change and its outlines per band class."""

_BANDED = (pb.GEOM_BOX, pb.GEOM_CYLINDER, pb.GEOM_CAPSULE, pb.GEOM_PLANE)
"""The shapes whose outlines :class:`_BandLevels` follows."""


OUTLINE_MEMO: Memo[tuple[Outline | None]] = Memo(8192)
"""Outlines of the shapes outlined in this process (``None``: the shape misses the band),
keyed by the bytes of every number the outline is computed from."""

_PRIMITIVES = (pb.GEOM_BOX, pb.GEOM_SPHERE, pb.GEOM_CYLINDER, pb.GEOM_CAPSULE)
_BAND = struct.Struct("<2d")
_SHAPE = struct.Struct("<i17d")


def _shape_key(shape: pbq.ShapeData, com_pose: tuple[Sequence[float], Sequence[float]]) -> bytes:
    """The bytes of a shape's type, size and frame, and of its link's centre-of-mass pose."""
    return _SHAPE.pack(
        shape.geometry_type, *shape.dimensions, *shape.local_position, *shape.local_orientation,
        *com_pose[0], *com_pose[1],
    )


def _shape_outline(
    client: int,
    body: int,
    link: int,
    index: int,
    shape: pbq.ShapeData,
    com: Frame,
    frame: Frame,
    ref_inv: Frame,
    band: ZBand,
) -> Outline | None:
    """The outline of the ``index``-th collision shape of a link (``com``: the link's
    centre-of-mass frame in the reference frame, ``frame`` the shape's)."""
    geom, dims = shape.geometry_type, shape.dimensions
    if geom == pb.GEOM_BOX:
        return _points_outline(_box_slice(frame, np.asarray(dims) / 2.0, band))
    if geom == pb.GEOM_SPHERE:
        return _sphere_slice(frame[0], float(dims[0]), band)
    if geom in (pb.GEOM_CYLINDER, pb.GEOM_CAPSULE):
        return _round_solid(frame, float(dims[0]), float(dims[1]), geom == pb.GEOM_CAPSULE, band)
    if geom == pb.GEOM_MESH:
        verts = pbq.mesh_vertices(client, body, link, index)
        if len(verts) == 0:  # PyBullet gives no vertices: the link's bounding box
            return _aabb_outline(client, body, link, ref_inv, band)
        return _mesh_outline(verts, com, band)
    return _aabb_outline(client, body, link, ref_inv, band)


def _mesh_outline(verts: np.ndarray, com: Frame, band: ZBand) -> Outline | None:
    """Mesh vertices come in the link's centre-of-mass frame, the shape's offset applied."""
    pts = com[0] + verts @ com[1].T
    z = pts[:, 2]
    if z.max() < band[0] or z.min() > band[1]:
        return None
    return _points_outline(pts[:, :2])
