"""The geometry of an IFC element as points in metres, and the box around them.

:func:`element_solid` gives the corner points and the volume of an element's body, in world
coordinates and metres. Simple bodies (extrusions of a rectangle or a polygon, the form walls,
slabs, plates and openings usually take) are read directly from their placement and profile;
anything else (meshes, mapped items, booleans, sweeps) goes through ifcopenshell's geometry
kernel. A body clipped by half-spaces (IfcBooleanClippingResult: a wall cut under a sloped
roof) is read as its uncut first operand: the cut only lowers its top.

:meth:`ShapeReader.points` gives an obstacle's points only (its footprint is their hull): read
directly from extrusions, clipped bodies, mapped items (each mapped representation read once and
kept for the next element that maps it), faceted breps and face sets, and from the kernel only
for anything else (curved sweeps, revolved solids). :meth:`ShapeReader.mesh` gives the kernel's
triangles, for a wall whose holes matter. :func:`footprint_box` fits the upright box of least
footprint around the points: its centre, size (length along its yaw, width, height) and yaw; a
body whose volume is much less than that box's is not box-like (a curved or L-shaped wall, a
tilted element).

A reader computes each placement once (object placements up their chains, the
IfcAxis2Placements of items and mapping origins, the mapped items' transformations), as
elements share them; a faceted body's points are those its references lead to, found by
ifcopenshell's own walk. Attributes are read by position
(:mod:`~bt_manip.bim.ifc_attributes`): by name, ifcopenshell takes several times longer.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Any

import numpy as np

from bt_manip.bim import ifc_attributes as at
from bt_manip.bim.grid_placement import UnreadGrid, grid_placement_matrix
from bt_manip.bim.hulls import distinct_chain, finite_rows, hull_xy, next_rows, unique_rows

__all__ = ["BOX_FILL", "Box", "ShapeReader", "Solid", "UnsupportedGeometry", "body_representation",
           "footprint_box", "hull_box", "hull_prism", "hull_xy", "is_box_like",
           "unique_rows"]

BOX_FILL = 0.9
"""A body is box-like when its volume is at least this share of its upright bounding box's
(less the mitres of :func:`is_box_like`)."""


MAX_PLACEMENT_CHAIN = 64
"""Placements relative to one another at most, from an element's to the first absolute one
(and representation maps nested in one another at most)."""


class UnsupportedGeometry(Exception):
    """The element's geometry cannot be read or is not what bt-manip models."""


@contextmanager
def _following(pending: dict[int, None], key: int, what: str) -> Iterator[None]:
    """Mark entity ``key`` as being read for the block, ``pending`` holding those of the chain
    being followed in order; UnsupportedGeometry naming the chain when ``key`` is already in
    it (a loop) or the chain is :data:`MAX_PLACEMENT_CHAIN` long."""
    if key in pending or len(pending) >= MAX_PLACEMENT_CHAIN:
        chain = " -> ".join(f"#{k}" for k in [*pending, key])
        why = "loop" if key in pending else f"go more than {MAX_PLACEMENT_CHAIN} deep"
        raise UnsupportedGeometry(f"its {what} {why} ({chain})")
    pending[key] = None
    try:
        yield
    finally:
        del pending[key]


@dataclass(frozen=True)
class Solid:
    """The points (N x 3, metres, world frame) and volume (m3) of an element's body."""

    points: np.ndarray
    volume: float


@dataclass(frozen=True)
class Box:
    """An upright box: centre (x, y, z), size (length along ``yaw``, width, height), yaw."""

    centre: tuple[float, float, float]
    size: tuple[float, float, float]
    yaw: float

    @property
    def bottom(self) -> float:
        return self.centre[2] - self.size[2] / 2

    @property
    def top(self) -> float:
        return self.centre[2] + self.size[2] / 2

    @property
    def volume(self) -> float:
        return self.size[0] * self.size[1] * self.size[2]

    def axis(self) -> tuple[float, float]:
        return (math.cos(self.yaw), math.sin(self.yaw))


class ShapeReader:
    """Reads element bodies of one IFC file; ``scale`` converts file lengths to metres."""

    def __init__(self, scale: float, model: Any = None,
                 shift: tuple[float, float] = (0.0, 0.0)) -> None:
        self.scale = scale
        self.model = model
        self.shift = shift
        """Subtracted (m) from the x and y of every point read (a model far from its
        origin, :attr:`~bt_manip.bim.ifc_input.IfcSource.shift`)."""
        self._settings: Any = None
        self._mapped: dict[int, np.ndarray | None] = {}
        self._placements: dict[int, np.ndarray] = {}
        self._pending: dict[int, None] = {}
        """Placements being computed, in the order of the chain (a loop is refused)."""
        self._pending_maps: dict[int, None] = {}
        """Representation maps being read, likewise."""
        self._axes: dict[int, np.ndarray] = {}
        self._mappings: dict[tuple[int, int], np.ndarray] = {}
        self._angle: float | None = None

    def placement(self, placement: Any) -> np.ndarray:
        """The 4x4 matrix (file units) of an object placement, each placement of a chain
        computed once per reader (elements share their storey's and building's): a local
        placement, or one on a design grid (:mod:`bt_manip.bim.grid_placement`);
        UnsupportedGeometry for any other kind (an IFC4.3 linear placement)."""
        import ifcopenshell.util.placement as util

        key = int(placement.id())
        found = self._placements.get(key)
        if found is not None:
            return found
        with _following(self._pending, key, "placements"):
            local = placement.is_a("IfcLocalPlacement")
            parent = placement.get_argument(at.PLACEMENT_REL_TO) if local else None
            if parent is not None:
                found = self.placement(parent) @ self.axis(
                    placement.get_argument(at.RELATIVE_PLACEMENT))
            elif local:
                found = np.asarray(util.get_local_placement(placement), dtype=float)
            elif placement.is_a("IfcGridPlacement"):
                try:
                    found = grid_placement_matrix(placement, self.placement)
                except UnreadGrid as exc:
                    raise UnsupportedGeometry(f"its grid placement: {exc}") from None
            else:
                raise UnsupportedGeometry(f"its placement ({placement.is_a()}) is not read")
        self._placements[key] = found
        return found

    def axis(self, placement: Any) -> np.ndarray:
        """The 4x4 matrix of an IfcAxis2Placement, computed once per reader (items and
        mapping origins often share theirs)."""
        import ifcopenshell.util.placement as util

        key = int(placement.id())
        found = self._axes.get(key)
        if found is None:
            found = _axis_matrix(placement)
            if found is None:
                found = np.asarray(util.get_axis2placement(placement), dtype=float)
            self._axes[key] = found
        return found

    def _position(self, item: Any) -> np.ndarray:
        """An extrusion's Position matrix (the identity without one)."""
        position = item.get_argument(at.POSITION)
        return self.axis(position) if position is not None else np.eye(4)

    def yaw(self, element: Any) -> float | None:
        """Heading of the element's placement x axis (None when it is vertical, or the element
        has no placement), from the placements computed once per reader."""
        placement = _object_placement(element)
        if placement is None:
            return None
        return _yaw_of(self.placement(placement))

    def solid(self, element: Any) -> Solid:
        """The element's body; UnsupportedGeometry when it has none or the kernel fails."""
        rep = body_representation(element)
        if rep is None:
            raise UnsupportedGeometry("it has no body geometry (no 'Body' representation)")
        fast = self._extrusions(element, rep)
        return fast if fast is not None else self._kernel(element)

    # -- simple extrusions, read directly -------------------------------------------------
    def _extrusions(self, element: Any, rep: Any) -> Solid | None:

        items = [_uncut(item) for item in rep.get_argument(at.ITEMS)]
        if not items or any(not item.is_a("IfcExtrudedAreaSolid") for item in items):
            return None
        placement = _object_placement(element)
        if placement is None:
            return None
        world = self.placement(placement)
        all_points: list[np.ndarray] = []
        volume = 0.0
        for item in items:
            profile = _profile_points(item.get_argument(at.SWEPT_AREA), self.axis)
            if profile is None:
                return None
            local = self._position(item)
            direction = _direction(item)
            norm = float(np.linalg.norm(direction))
            if norm < 1e-12 or len(direction) != 3:
                return None
            direction = direction / norm * float(item.get_argument(at.DEPTH))
            base = np.column_stack([profile, np.zeros(len(profile)), np.ones(len(profile))])
            top = base.copy()
            top[:, :3] += direction
            pts = (world @ local @ np.vstack([base, top]).T).T[:, :3]
            all_points.append(pts)
            volume += _polygon_area(profile) * abs(float(direction[2]))
        points = self._shifted(np.vstack(all_points) * self.scale)
        return Solid(points, volume * self.scale**3)

    # -- anything else, through the geometry kernel -----------------------------------------
    def _kernel(self, element: Any) -> Solid:
        verts, faces = self.mesh(element)
        a, b, c = verts[faces[:, 0]], verts[faces[:, 1]], verts[faces[:, 2]]
        volume = abs(float(np.einsum("ij,ij->i", a, np.cross(b, c)).sum()) / 6.0)
        return Solid(verts, volume)

    def mesh(self, element: Any) -> tuple[np.ndarray, np.ndarray]:
        """The kernel's triangles of the element's body: vertices (N x 3, metres, world) and
        faces (M x 3 indices); openings are not subtracted."""
        import ifcopenshell.geom

        rep = body_representation(element)
        if rep is None:
            raise UnsupportedGeometry("it has no body geometry (no 'Body' representation)")
        # what the kernel would follow round a loop forever (or crash on): refused first
        placement = _object_placement(element)
        if placement is not None:
            self.placement(placement)
        check_nesting(rep.get_argument(at.ITEMS))
        if self._settings is None:
            settings = ifcopenshell.geom.settings()
            settings.set("use-world-coords", True)
            settings.set("disable-opening-subtractions", True)
            self._settings = settings
        try:
            shape: Any = ifcopenshell.geom.create_shape(self._settings, element)
        except Exception as exc:  # the kernel raises RuntimeError and others
            raise UnsupportedGeometry(f"the geometry kernel cannot read it ({exc})") from None
        verts = self._shifted(np.asarray(shape.geometry.verts, dtype=float).reshape(-1, 3))
        faces = np.asarray(shape.geometry.faces, dtype=int).reshape(-1, 3)
        if len(verts) == 0 or len(faces) == 0:
            raise UnsupportedGeometry("its body geometry is empty")
        return verts, faces

    # -- points only, for obstacles ------------------------------------------------------------
    def points(self, element: Any) -> np.ndarray:
        """The points (N x 3, metres, world) of the element's body, read directly where the
        items allow it, else from the kernel; UnsupportedGeometry when there is no body."""

        rep = body_representation(element)
        if rep is None:
            raise UnsupportedGeometry("it has no body geometry (no 'Body' representation)")
        placement = _object_placement(element)
        if placement is not None:
            world = self.placement(placement)
            parts = [self._item_points(item) for item in rep.get_argument(at.ITEMS)]
            if parts and all(p is not None and len(p) for p in parts):
                local = np.vstack([p for p in parts if p is not None])
                pts: np.ndarray = (local @ world[:3, :3].T + world[:3, 3]) * self.scale
                return self._shifted(pts)
        return self.mesh(element)[0]

    def _shifted(self, points: np.ndarray) -> np.ndarray:
        """``points`` (N x 3, metres, the model's) in the world: less :attr:`shift`."""
        if self.shift != (0.0, 0.0):
            points[:, 0] -= self.shift[0]
            points[:, 1] -= self.shift[1]
        return points

    def _source_points(self, representation: Any) -> np.ndarray | None:
        """A mapped representation's points, read once per file: directly, else from the
        kernel's mesh of the representation itself (not of each element mapping it); only
        the corners of their footprint's hull are kept, at the lowest and highest z."""
        parts = [self._item_points(i) for i in representation.get_argument(at.ITEMS)]
        if parts and all(p is not None and len(p) for p in parts):
            pts = np.vstack([p for p in parts if p is not None])
        else:
            import ifcopenshell.geom

            check_nesting(representation.get_argument(at.ITEMS))
            try:
                shape: Any = ifcopenshell.geom.create_shape(ifcopenshell.geom.settings(),
                                                            representation)
            except Exception:  # the kernel raises RuntimeError and others
                return None
            verts = getattr(shape, "verts", None)
            if verts is None:
                verts = shape.geometry.verts
            pts = np.asarray(verts, dtype=float).reshape(-1, 3) / self.scale
            if len(pts) == 0:
                return None
        return hull_prism(pts)

    def _mapping(self, item: Any) -> np.ndarray:
        """The transformation of a mapped item (as ifcopenshell.util.placement's
        get_mappeditem_transformation), kept per reader for each pair of transformation
        operator and mapped representation: exporters give many mapped items one operator
        (often the identity) and one representation."""
        import ifcopenshell.util.placement as placement

        source = item.get_argument(at.MAPPING_SOURCE)
        target = item.get_argument(at.MAPPING_TARGET)
        key = (int(target.id()), int(source.id()))
        found = self._mappings.get(key)
        if found is None:
            origin = self.axis(source.get_argument(at.MAPPING_ORIGIN))
            if target.is_a("IfcCartesianTransformationOperator3D"):
                found = np.asarray(_operator_matrix(target) @ origin, dtype=float)
            else:
                found = np.asarray(placement.get_mappeditem_transformation(item), dtype=float)
            self._mappings[key] = found
        return found

    @property
    def angle_unit(self) -> float | None:
        """Radians per plane-angle unit of the file (None without a model)."""
        if self._angle is None and self.model is not None:
            import ifcopenshell.util.unit

            self._angle = float(ifcopenshell.util.unit.calculate_unit_scale(self.model,
                                                                             "PLANEANGLEUNIT"))
        return self._angle

    def _item_points(self, item: Any) -> np.ndarray | None:
        """Points of one representation item in its representation's frame (file units)."""

        item = _uncut(item)
        if item.is_a("IfcExtrudedAreaSolid"):
            profile = _profile_points(item.get_argument(at.SWEPT_AREA), self.axis,
                                      self.angle_unit)
            if profile is None:
                return None
            local = self._position(item)
            direction = _direction(item)
            norm = float(np.linalg.norm(direction))
            if norm < 1e-12 or len(direction) != 3:
                return None
            base = np.column_stack([profile, np.zeros(len(profile))])
            prism = np.vstack([base, base + direction / norm * float(item.get_argument(at.DEPTH))])
            out: np.ndarray = prism @ local[:3, :3].T + local[:3, 3]
            return out
        if item.is_a("IfcMappedItem"):
            source = item.get_argument(at.MAPPING_SOURCE)
            key = int(source.id())
            if key not in self._mapped:
                with _following(self._pending_maps, key, "mapped representations"):
                    self._mapped[key] = self._source_points(
                        source.get_argument(at.MAPPED_REPRESENTATION))
            mapped = self._mapped[key]
            if mapped is None:
                return None
            m = self._mapping(item)
            moved: np.ndarray = mapped @ m[:3, :3].T + m[:3, 3]
            return moved
        if item.is_a("IfcTessellatedFaceSet"):
            return np.asarray(item.get_argument(at.COORDINATES).get_argument(at.COORDINATES),
                              dtype=float)
        if item.is_a() in _POINT_SETS and self.model is not None:
            # every point the item refers to, each once: the corners of its polygon loops (or
            # of whatever else bounds its faces); found by ifcopenshell's own walk of the
            # references, which costs about half of walking faces, bounds and loops in Python
            coords = [p.get_argument(at.COORDINATES) for p in self.model.traverse(item)
                      if p.is_a() == "IfcCartesianPoint"]
            if not coords or any(len(c) != 3 for c in coords):
                return None
            return np.asarray(coords, dtype=float)
        return None


NOT_BODY = {"Axis", "FootPrint", "Box", "Annotation", "Profile", "Plan", "Reference",
            "Clearance", "CoG", "Surface", "Lighting"}
"""Representation identifiers that are not an element's body."""


_POINT_SETS = {"IfcFacetedBrep", "IfcFacetedBrepWithVoids", "IfcFaceBasedSurfaceModel",
               "IfcShellBasedSurfaceModel"}
"""Items whose points are their polygon loops' points (no curved faces)."""


def _axis_matrix(placement: Any) -> np.ndarray | None:
    """An IfcAxis2Placement3D's or IfcAxis2Placement2D's matrix, the same numbers as
    ifcopenshell.util.placement's ``get_axis2placement`` (the same operations in the same
    order, the cross product written out); None for any other placement, or one whose
    coordinates are not of its dimension.

    A 2D placement's direction is padded with a zero here, where ifcopenshell resizes the
    array in place: that raises whenever a profiler or a tracer holds a reference to it."""
    kind = placement.is_a()
    if kind not in ("IfcAxis2Placement3D", "IfcAxis2Placement2D"):
        return None
    location = placement.get_argument(at.LOCATION)
    if location is None or not location.is_a("IfcCartesianPoint"):
        return None
    origin = location.get_argument(at.COORDINATES)
    if not origin:
        return None
    if kind == "IfcAxis2Placement3D":
        axis = placement.get_argument(at.AXIS)
        ref = placement.get_argument(at.REF_DIRECTION_3D)
        z = np.array(axis.get_argument(at.DIRECTION_RATIOS) if axis else (0, 0, 1))
        x = np.array(ref.get_argument(at.DIRECTION_RATIOS) if ref else (1, 0, 0))
    else:
        ref = placement.get_argument(at.REF_DIRECTION_2D)
        ratios = tuple(ref.get_argument(at.DIRECTION_RATIOS)) if ref else (1, 0)
        if len(origin) != 2 or len(ratios) != 2:
            return None
        z = np.array((0, 0, 1))
        x = np.array((*ratios, 0.0) if ref else (1, 0, 0))
        origin = (*origin, 0.0)
    return _frame(origin, z, x)


def _frame(origin: Any, z: np.ndarray, x: np.ndarray) -> np.ndarray:
    """The 4x4 matrix of the frame at ``origin`` whose z and x axes point along ``z`` and
    ``x``: ifcopenshell.util.placement's ``a2p``, its operations in the same order (the cross
    product written out, the same numbers as numpy's).

    The usual frame (three coordinates each, axes of finite non-zero length, not parallel) is
    computed in Python floats: each length is the square root of numpy's dot product of the
    axis with itself, as ``np.linalg.norm`` computes it, and each quotient and product is the
    same IEEE operation numpy does; any other goes through numpy, warnings and all."""
    if len(x) == 3 and len(z) == 3 and len(origin) == 3:
        nx, nz = math.sqrt(x.dot(x)), math.sqrt(z.dot(z))
        if 0.0 < nx < math.inf and 0.0 < nz < math.inf:
            x0, x1, x2 = (v / nx for v in x.tolist())
            z0, z1, z2 = (v / nz for v in z.tolist())
            y = np.array((z1 * x2 - z2 * x1, z2 * x0 - z0 * x2, z0 * x1 - z1 * x0))
            ny = math.sqrt(y.dot(y))
            if 0.0 < ny < math.inf:
                y0, y1, y2 = (v / ny for v in y.tolist())
                o0, o1, o2 = (float(v) for v in origin)
                m = np.array(((x0, x1, x2, 0.0), (y0, y1, y2, 0.0), (z0, z1, z2, 0.0),
                              (o0, o1, o2, 1.0)))
                fast: np.ndarray = m.T
                return fast
    return _frame_numpy(origin, z, x)


def _frame_numpy(origin: Any, z: np.ndarray, x: np.ndarray) -> np.ndarray:
    """:func:`_frame` in numpy's own operations, for any frame."""
    x = x / np.linalg.norm(x)
    z = z / np.linalg.norm(z)
    y = np.array([z[1] * x[2] - z[2] * x[1], z[2] * x[0] - z[0] * x[2],
                  z[0] * x[1] - z[1] * x[0]])
    y = y / np.linalg.norm(y)
    m = np.eye(4)
    m[:-1, :-1] = x, y, z
    m[-1, :-1] = origin
    out: np.ndarray = m.T
    return out


def _operator_matrix(operator: Any) -> np.ndarray:
    """An IfcCartesianTransformationOperator3D's matrix (and its non-uniform subtype's): the
    same numbers as ifcopenshell.util.placement's ``get_cartesiantransformationoperator3d``,
    from the same operations in the same order."""
    origin = np.array(operator.get_argument(at.LOCAL_ORIGIN).get_argument(at.COORDINATES))
    axes = [np.array((1.0, 0.0, 0.0)), np.array((0.0, 1.0, 0.0)), np.array((0.0, 0.0, 1.0))]
    for k, position in enumerate((at.AXIS1, at.AXIS2, at.AXIS3)):
        given = operator.get_argument(position)
        if given:
            axes[k][0:3] = given.get_argument(at.DIRECTION_RATIOS)
    m = _frame(origin, axes[2], axes[0])
    if m.T[1][0:3].dot(axes[1]) < 0.0:  # a mirrored y axis
        m.T[1] *= -1.0
    scale1 = operator.get_argument(at.SCALE) or 1.0
    scale2 = scale3 = scale1
    if operator.is_a("IfcCartesianTransformationOperator3DnonUniform"):
        given2, given3 = operator.get_argument(at.SCALE2), operator.get_argument(at.SCALE3)
        scale2 = given2 if given2 is not None else scale1
        scale3 = given3 if given3 is not None else scale1
    m.T[0] *= scale1
    m.T[1] *= scale2
    m.T[2] *= scale3
    return m


def _nested(item: Any) -> list[Any]:
    """The geometry ``item`` is made of, where it may nest: a mapped item's mapped
    representation's items, a boolean result's operands, a CSG solid's tree, a swept solid's
    profile and directrix, a profile's curves or parent profiles, a composite curve's
    segments' curves, a trimmed or offset curve's basis, a geometric set's elements. (Faces,
    loops and points hold nothing that nests.)"""
    def some(*values: Any) -> list[Any]:
        return [v for v in values if v is not None]

    if item.is_a("IfcMappedItem"):
        source = item.MappingSource
        rep = source.MappedRepresentation if source is not None else None
        return list(rep.Items or ()) if rep is not None else []
    if item.is_a("IfcBooleanResult"):
        return some(item.FirstOperand, item.SecondOperand)
    if item.is_a("IfcCsgSolid"):
        return some(item.TreeRootExpression)
    if item.is_a("IfcSweptAreaSolid"):
        return some(item.SweptArea, getattr(item, "Directrix", None))
    if item.is_a("IfcSweptDiskSolid"):
        return some(item.Directrix)
    if item.is_a("IfcArbitraryClosedProfileDef"):
        return some(item.OuterCurve, *(getattr(item, "InnerCurves", None) or ()))
    if item.is_a("IfcArbitraryOpenProfileDef"):
        return some(item.Curve)
    if item.is_a("IfcCompositeProfileDef"):
        return some(*(item.Profiles or ()))
    if item.is_a("IfcDerivedProfileDef"):
        return some(item.ParentProfile)
    if item.is_a("IfcCompositeCurve"):
        return some(*(getattr(s, "ParentCurve", None) for s in item.Segments or ()))
    if item.is_a("IfcTrimmedCurve") or item.is_a("IfcOffsetCurve2D") or \
            item.is_a("IfcOffsetCurve3D"):
        return some(item.BasisCurve)
    if item.is_a("IfcGeometricSet"):
        return some(*(item.Elements or ()))
    return []


def check_nesting(items: Any) -> None:
    """UnsupportedGeometry when the items' geometry nests in a loop (:func:`_nested`: a mapped
    representation that maps itself, a composite curve that is its own segment) or more than
    :data:`MAX_PLACEMENT_CHAIN` deep: the geometry kernel would crash on it."""
    done: set[int] = set()
    stack: list[tuple[Any, int]] = [(item, 0) for item in items or ()]
    path: list[int] = []
    while stack:
        item, depth = stack.pop()
        del path[depth:]
        key = int(item.id())
        if key in path:
            chain = " -> ".join(f"#{k}" for k in [*path[path.index(key):], key])
            raise UnsupportedGeometry(f"its geometry nests in a loop ({chain})")
        if depth >= MAX_PLACEMENT_CHAIN:
            raise UnsupportedGeometry(
                f"its geometry nests more than {MAX_PLACEMENT_CHAIN} deep")
        if key in done:
            continue
        done.add(key)
        path.append(key)
        stack += [(child, depth + 1) for child in _nested(item)]


def _uncut(item: Any) -> Any:
    """The first operand under half-space clippings (the body before the cut)."""
    for _ in range(64):
        if not item.is_a("IfcBooleanClippingResult"):
            return item
        item = item.get_argument(at.FIRST_OPERAND)
    return item


def body_representation(element: Any) -> Any:
    """The element's 'Body' shape representation, else the first one that is not a known
    other kind (an axis, a footprint, a bounding box...), else None."""
    if element.is_a("IfcProduct"):
        shape = element.get_argument(at.REPRESENTATION)
    else:
        shape = getattr(element, "Representation", None)
    if shape is None:
        return None
    reps = [(rep, rep.get_argument(at.REPRESENTATION_IDENTIFIER))
            for rep in shape.get_argument(at.REPRESENTATIONS)]
    for rep, identifier in reps:
        if identifier == "Body":
            return rep
    for rep, identifier in reps:
        if identifier not in NOT_BODY:
            return rep
    return None


def _object_placement(element: Any) -> Any:
    """The element's ObjectPlacement (None when it has none)."""
    if element.is_a("IfcProduct"):
        return element.get_argument(at.OBJECT_PLACEMENT)
    return getattr(element, "ObjectPlacement", None)


def _direction(item: Any) -> np.ndarray:
    """An extrusion's direction ratios."""
    ratios = item.get_argument(at.EXTRUDED_DIRECTION).get_argument(at.DIRECTION_RATIOS)
    return np.asarray(ratios, dtype=float)


def _profile_points(profile: Any, axis: Any = None,
                    angle_unit: float | None = None) -> np.ndarray | None:
    """The 2D outline of a rectangle or polygon profile, in its own frame; None otherwise.
    ``axis`` gives an IfcAxis2Placement's matrix (ifcopenshell's, computed anew, without).
    With ``angle_unit`` (radians per the file's plane-angle unit), an outline with circular
    arcs is read too (a composite curve of polylines and arcs, :func:`_composite_points`, or
    an indexed poly curve with arc segments, :func:`_indexed_points`), each arc as points of a
    polygon that encloses it, and a profile with voids by its outer curve: the points of an
    obstacle's footprint, not an outline whose area counts."""
    import ifcopenshell.util.placement as placement

    if profile.is_a("IfcRectangleProfileDef") and not profile.is_a("IfcRoundedRectangleProfileDef"):
        hx = float(profile.get_argument(at.X_DIM)) / 2
        hy = float(profile.get_argument(at.Y_DIM)) / 2
        pts = np.array([[-hx, -hy], [hx, -hy], [hx, hy], [-hx, hy]])
    elif profile.is_a("IfcCircleProfileDef") and not profile.is_a("IfcCircleHollowProfileDef"):
        # the 32-gon round the circle, its sides tangent to it (and four of them upright)
        angles = (np.arange(32) + 0.5) * (2 * math.pi / 32)
        radius = float(profile.get_argument(at.RADIUS)) / math.cos(math.pi / 32)
        pts = np.column_stack([radius * np.cos(angles), radius * np.sin(angles)])
    elif profile.is_a("IfcArbitraryClosedProfileDef") and (
        angle_unit is not None or not profile.is_a("IfcArbitraryProfileDefWithVoids")
    ):
        # a profile with voids is read by its outer curve for a footprint: the voids lie
        # within it, so they change neither the hull of the points nor their heights
        curve = profile.get_argument(at.OUTER_CURVE)
        if curve.is_a("IfcPolyline"):
            pts = _polyline_points(curve)
        elif curve.is_a("IfcIndexedPolyCurve"):
            found = _indexed_points(curve, angle_unit is not None)
            if found is None:
                return None
            pts = found
        elif curve.is_a("IfcCompositeCurve") and angle_unit is not None:
            found = _composite_points(curve, angle_unit, axis)
            if found is None:
                return None
            pts = found
        else:
            return None
        if len(pts) > 1 and _close(pts[0], pts[-1]):
            pts = pts[:-1]
        if len(pts) < 3:
            return None
    else:
        return None
    # only the parameterised profiles (the rectangle and the circle here) have a Position
    position = (profile.get_argument(at.PROFILE_POSITION)
                if profile.is_a("IfcParameterizedProfileDef") else None)
    if position is not None:
        m = (axis(position) if axis is not None
             else np.asarray(placement.get_axis2placement(position), dtype=float))
        pts = pts @ m[:2, :2].T + m[:2, 3]
    return pts


ARC_STEP = math.radians(5.0)
"""Largest angle between two points read off a circular arc."""


def _composite_points(curve: Any, angle_unit: float, axis: Any) -> np.ndarray | None:
    """The points of a 2D composite curve of polylines and trimmed circles (the outlines of
    Revit's stairs and rolled steel sections): each polyline's points, and for each arc points
    at most :data:`ARC_STEP` apart on the circle enlarged by ``1 / cos(step / 2)``, so the
    polygon through them encloses the arc. None for any other segment (a B-spline, an arc
    trimmed by points, a basis curve that is not a circle)."""
    chunks: list[np.ndarray] = []
    for segment in curve.get_argument(at.SEGMENTS):
        parent = segment.get_argument(at.PARENT_CURVE)
        if parent.is_a("IfcPolyline"):
            chunks.append(_polyline_points(parent))
            continue
        if not parent.is_a("IfcTrimmedCurve"):
            return None
        circle = parent.get_argument(at.BASIS_CURVE)
        if not circle.is_a("IfcCircle"):
            return None
        position = circle.get_argument(at.CIRCLE_POSITION)
        if position is None:
            return None
        trims = []
        for trim in (parent.get_argument(at.TRIM1), parent.get_argument(at.TRIM2)):
            values = [t.get_argument(0) for t in trim if t.is_a("IfcParameterValue")]
            if not values:
                return None
            trims.append(float(values[0]) * angle_unit)
        t1, t2 = trims
        # the arc runs from Trim1 to Trim2, counter-clockwise when the sense agrees
        sweep = (t2 - t1) % (2 * math.pi) if parent.get_argument(at.SENSE_AGREEMENT) else \
            -((t1 - t2) % (2 * math.pi))
        local = _arc_points(float(circle.get_argument(at.CIRCLE_RADIUS)), t1, sweep)
        m = axis(position)
        chunks.append(local @ m[:2, :2].T + m[:2, 3])
    if not chunks:
        return None
    return np.vstack(chunks)


def _arc_points(radius: float, start: float, sweep: float) -> np.ndarray:
    """Points (N x 2, about the centre) of a polygon enclosing the arc of ``radius`` from the
    angle ``start`` through ``sweep`` (negative: clockwise): at most :data:`ARC_STEP` apart, on
    the circle enlarged by ``1 / cos(step / 2)``, the first and last on the arc's ends' rays."""
    n = max(1, math.ceil(abs(sweep) / ARC_STEP))
    angles = start + sweep * np.arange(n + 1) / n
    enclosing = radius / math.cos(abs(sweep) / n / 2)
    return np.column_stack([enclosing * np.cos(angles), enclosing * np.sin(angles)])


def _indexed_points(curve: Any, arcs: bool) -> np.ndarray | None:
    """The points (N x 2) of an IfcIndexedPolyCurve: its points in turn without segments, else
    those each segment lists (a point shared by two segments once); an arc segment (three
    points: start, one on the arc, end) read as a polygon enclosing the arc when ``arcs``
    (a footprint), else None, as for an index off the point list or another kind of segment
    (then the geometry kernel reads the curve). Bonsai writes its profiles this way."""
    coords = curve.get_argument(at.POINTS).get_argument(at.COORDINATES)
    segments = curve.get_argument(at.INDEXED_SEGMENTS)
    if segments is None:
        return np.array([c[:2] for c in coords], dtype=float)
    out: list[tuple[float, float]] = []
    for segment in segments:
        kind = segment.is_a()
        indices = segment.get_argument(0)
        if not indices or any(not 1 <= i <= len(coords) for i in indices):
            return None
        points = [(float(coords[i - 1][0]), float(coords[i - 1][1])) for i in indices]
        if kind == "IfcLineIndex" and len(points) >= 2:
            chunk = points
        elif kind == "IfcArcIndex" and arcs and len(points) == 3:
            found = _arc_through(*points)
            if found is None:
                return None
            chunk = [(float(x), float(y)) for x, y in found]
        else:
            return None
        out.extend(chunk[1:] if out and out[-1] == chunk[0] else chunk)
    return np.array(out, dtype=float)


def _arc_through(a: tuple[float, float], b: tuple[float, float], c: tuple[float, float],
                 ) -> np.ndarray | None:
    """:func:`_arc_points` (in the points' frame) of the circular arc from ``a`` through ``b``
    to ``c``; None when the three are on one line (no circle passes through them)."""
    (ax, ay), (bx, by), (cx, cy) = a, b, c
    d = 2.0 * (ax * (by - cy) + bx * (cy - ay) + cx * (ay - by))
    span = max(abs(ax - cx), abs(ay - cy), abs(ax - bx), abs(ay - by))
    if abs(d) <= 1e-12 * max(span, 1e-300) ** 2:
        return None
    a2, b2, c2 = ax * ax + ay * ay, bx * bx + by * by, cx * cx + cy * cy
    ox = (a2 * (by - cy) + b2 * (cy - ay) + c2 * (ay - by)) / d
    oy = (a2 * (cx - bx) + b2 * (ax - cx) + c2 * (bx - ax)) / d
    t_a = math.atan2(ay - oy, ax - ox)
    t_b = math.atan2(by - oy, bx - ox)
    t_c = math.atan2(cy - oy, cx - ox)
    # counter-clockwise from a to c when b lies on that way round, else clockwise
    ccw = (t_b - t_a) % (2 * math.pi) <= (t_c - t_a) % (2 * math.pi)
    sweep = (t_c - t_a) % (2 * math.pi) if ccw else -((t_a - t_c) % (2 * math.pi))
    out: np.ndarray = _arc_points(math.hypot(ax - ox, ay - oy), t_a, sweep) + np.array([ox, oy])
    return out


def _close(a: np.ndarray, b: np.ndarray) -> bool:
    """``np.allclose(a, b)`` of two points: the same test (``|a - b| <= 1e-8 + 1e-5 * |b|``
    for each coordinate) without numpy's setup, for finite coordinates."""
    pairs = list(zip(a.tolist(), b.tolist(), strict=True))
    if not all(math.isfinite(u) and math.isfinite(v) for u, v in pairs):
        return bool(np.allclose(a, b))
    return all(abs(u - v) <= 1e-08 + 1e-05 * abs(v) for u, v in pairs)


def _polyline_points(polyline: Any) -> np.ndarray:
    """The x and y of an IfcPolyline's points."""
    return np.array([p.get_argument(at.COORDINATES)[:2]
                     for p in polyline.get_argument(at.POINTS)], dtype=float)


def _polygon_area(pts: np.ndarray) -> float:
    x, y = pts[:, 0], pts[:, 1]
    return abs(float(np.dot(x, next_rows(y)) - np.dot(y, next_rows(x)))) / 2.0


def footprint_box(points: np.ndarray, hint_yaw: float | None = None) -> Box:
    """The upright box of least footprint around ``points``, its length along its yaw.

    The yaw follows the longer horizontal side; of its two senses the one nearer ``hint_yaw``
    (the element's placement x axis) is taken, so a wall keeps the direction it was drawn in.

    The box is the least of the boxes along the edges of the points' hull, the first of them
    in Qhull's order when several are within 1e-9 m2 of the least. The hull of a few points
    is found without Qhull (:func:`~bt_manip.bim.hulls.monotone_chain`): its edges are
    Qhull's, in the same turn but from another corner, which changes nothing unless boxes
    along different angles tie; only then is Qhull asked for its order.
    """
    z0, z1 = float(points[:, 2].min()), float(points[:, 2].max())
    return _fit_box(points[:, :2], hint_yaw, z0, z1)


def hull_box(corners: np.ndarray, hint_yaw: float | None = None) -> Box:
    """:func:`footprint_box` of the points at z 0 whose x and y are ``corners`` (N x 2, a
    footprint's hull as :func:`~bt_manip.bim.hulls.hull_xy` gives it): the same box, of no
    height, without stacking the corners with their z first."""
    return _fit_box(corners, hint_yaw, 0.0, 0.0)


def _fit_box(xy: np.ndarray, hint_yaw: float | None, z0: float, z1: float) -> Box:
    """:func:`footprint_box` of the points ``xy`` (N x 2) whose lowest and highest z are
    ``z0`` and ``z1``."""
    chain = _chain_hull(xy)
    found = _least_box(xy, _edge_angles(chain)) if chain is not None else None
    if found is None or not found[3]:  # Qhull's order decides
        found = _least_box(xy, _candidate_angles(xy))
    angle, lo, hi, _ = found
    return _box_along(angle, lo, hi, hint_yaw, z0, z1)


def _box_along(angle: float, lo: tuple[float, float], hi: tuple[float, float],
               hint_yaw: float | None, z0: float, z1: float) -> Box:
    """The box from ``lo`` to ``hi`` along (u) and across (v) ``angle``, from ``z0`` to
    ``z1``: its length along its yaw, the sense of the yaw the one nearer ``hint_yaw``."""
    a0 = angle
    length, width = hi[0] - lo[0], hi[1] - lo[1]
    if width > length:
        angle += math.pi / 2
        length, width = width, length
    if hint_yaw is not None and math.cos(angle - hint_yaw) < 0:
        angle += math.pi
    angle = math.atan2(math.sin(angle), math.cos(angle))
    mid_u, mid_v = (lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2
    cx = mid_u * math.cos(a0) - mid_v * math.sin(a0)
    cy = mid_u * math.sin(a0) + mid_v * math.cos(a0)
    return Box((cx, cy, (z0 + z1) / 2), (length, width, z1 - z0), angle)


TIE = 1e-9
"""Boxes whose footprints differ by less than this (m2) are equally small."""
SMALL_BOX = 96
"""The boxes of at most this many points times angles are measured in Python floats, larger
sets by numpy (the same numbers either way)."""

Extent = tuple[float, float, float, float]
"""The least and greatest coordinates of points along an angle (u) and across it (v):
``(u0, u1, v0, v1)``."""


def _least_box(xy: np.ndarray, angles: list[float],
               ) -> tuple[float, tuple[float, float], tuple[float, float], bool]:
    """The angle, and the low and high corners (along and across it), of the least of the
    boxes along ``angles``: the first of the least, as :data:`TIE` apart; and whether that
    box is the same in any order of ``angles`` (False when boxes within twice the tie of the
    least lie along angles that are not all the same number)."""
    extents = _extents_py(xy, angles) if len(xy) * len(angles) <= SMALL_BOX else None
    if extents is None:
        extents = _extents_np(xy, angles)
    areas = [(u1 - u0) * (v1 - v0) for u0, u1, v0, v1 in extents]
    # the pick is one of the boxes within TIE of the least, whatever the order: when they all
    # lie along the same angle, it is the same box
    limit = min(areas) + 2 * TIE
    near = [a for a, area in zip(angles, areas, strict=True) if area <= limit]
    order_free = all(a == near[0] for a in near)
    pick = 0
    for k in range(1, len(angles)):  # the first of the least, as TIE apart
        if areas[k] < areas[pick] - TIE:
            pick = k
    u0, u1, v0, v1 = extents[pick]
    return angles[pick], (u0, v0), (u1, v1), order_free


def _extents_np(xy: np.ndarray, angles: list[float]) -> list[Extent]:
    """The extents of the points along and across each angle, every candidate at once."""
    c = [math.cos(a) for a in angles]
    s = [math.sin(a) for a in angles]
    x, y = xy[:, :1], xy[:, 1:2]
    # u = x cos + y sin and v = y cos - x sin (the same sums: x (-sin) is -(x sin)) side by side
    both = x * np.array(c + [-b for b in s]) + y * np.array(s + c)
    k = len(angles)
    lows, highs = both.min(axis=0).tolist(), both.max(axis=0).tolist()
    if 0.0 in lows or 0.0 in highs:  # which zero numpy's reduction keeps depends on its shape
        return _extents_apart(xy, angles)
    return list(zip(lows[:k], highs[:k], lows[k:], highs[k:], strict=True))


def _extents_apart(xy: np.ndarray, angles: list[float]) -> list[Extent]:
    """:func:`_extents_np` reduced along and across the angles apart (the sign of a zero
    extreme as each reduction gives it)."""
    c = np.array([math.cos(a) for a in angles])
    s = np.array([math.sin(a) for a in angles])
    x, y = xy[:, :1], xy[:, 1:2]
    u = x * c + y * s
    v = y * c - x * s
    return list(zip(u.min(axis=0).tolist(), u.max(axis=0).tolist(),
                    v.min(axis=0).tolist(), v.max(axis=0).tolist(), strict=True))


def _extents_py(xy: np.ndarray, angles: list[float]) -> list[Extent] | None:
    """:func:`_extents_np` of a few points, in Python floats: the same products, sums and
    extremes; None when they would not be the same numbers (a coordinate that is not finite,
    or an extreme that is zero, whose sign numpy's reduction picks its own way)."""
    rows = xy.tolist()
    if not finite_rows(rows):  # else numpy's extremes (of a NaN, say)
        return None
    found: dict[float, Extent] = {}  # an angle met again (a box's opposite sides) is known
    out = []
    for a in angles:
        extent = found.get(a)
        if extent is None:
            c, s = math.cos(a), math.sin(a)
            us = [x * c + y * s for x, y in rows]
            vs = [y * c - x * s for x, y in rows]
            extent = (min(us), max(us), min(vs), max(vs))
            if 0.0 in extent:  # numpy's sign of zero
                return _extents_apart(xy, angles)
            found[a] = extent
        out.append(extent)
    return out


def _chain_hull(xy: np.ndarray) -> np.ndarray | None:
    """The corners, counter-clockwise, of the hull :func:`_candidate_angles` takes the edges
    of, when it has few points and at least three corners (else None: Qhull's case)."""
    _, chain = distinct_chain(np.round(xy, 6))
    return chain if chain is not None and len(chain) >= 3 else None


def _edge_angles(hull: np.ndarray) -> list[float]:
    """The directions, modulo 90 degrees, of the edges of a polygon (corners in turn)."""
    edges = next_rows(hull) - hull
    return [a % (math.pi / 2) for a in np.arctan2(edges[:, 1], edges[:, 0]).tolist()]


def _candidate_angles(xy: np.ndarray) -> list[float]:
    """Edge directions of the convex hull of ``xy`` (one of them bounds the least box), in
    Qhull's order."""
    from scipy.spatial import ConvexHull, QhullError

    pts = unique_rows(np.round(xy, 6))
    if len(pts) < 3:
        if len(pts) == 2:
            d = pts[1] - pts[0]
            return [math.atan2(d[1], d[0])]
        return [0.0]
    try:
        hull = pts[ConvexHull(pts).vertices]
    except QhullError:  # collinear points
        d = pts[-1] - pts[0]
        return [math.atan2(d[1], d[0])]
    return _edge_angles(hull)


def hull_prism(points: np.ndarray) -> np.ndarray:
    """The corners of the hull of the points' footprint, each at their lowest and highest z:
    the points an upright obstacle's footprint and height depend on (as long as it is only
    turned about z)."""
    xy = hull_xy(points[:, :2])
    z0, z1 = float(points[:, 2].min()), float(points[:, 2].max())
    return np.vstack([np.column_stack([xy, np.full(len(xy), z0)]),
                      np.column_stack([xy, np.full(len(xy), z1)])])


def _yaw_of(m: np.ndarray) -> float | None:
    """Heading of a placement matrix's x axis, None when it is vertical."""
    x = m[:3, 0]
    if math.hypot(x[0], x[1]) < 1e-6:
        return None
    return math.atan2(x[1], x[0])


def is_box_like(solid: Solid, box: Box) -> bool:
    """Whether the body fills its upright box (see :data:`BOX_FILL`).

    A long body (at least twice as long as wide) may also miss a width-square prism at its
    ends: walls meeting at a corner are often cut at 45 degrees there.
    """
    length, width, height = box.size
    mitres = width * width * height if length >= 2 * width else 0.0
    return box.volume > 0 and solid.volume >= BOX_FILL * box.volume - mitres
