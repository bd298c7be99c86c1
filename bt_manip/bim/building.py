"""The building of one storey: walls with their openings, spaces, furniture and floor extent.

Walls come from IfcWall (and its subtypes, IfcWallStandardCase included) as straight segments
along the long side of their box, with the openings that void them (IfcRelVoidsElement), filled
or not by an IfcDoor or IfcWindow (IfcRelFillsElement). An opening is a passage for the robot
when it starts at the floor and reaches :data:`PASSAGE_HEIGHT` (or the top of a lower wall);
any other opening (a window, a hatch) cuts the wall but leaves a sill below it and a lintel
above it as static boxes, so the robot cannot drive through. Spaces (IfcSpace) become named
poses, furniture (IfcFurnishingElement) boxes around its geometry, and slabs (IfcSlab) give the
floor's extent. Elevations are measured from the storey's placement, which is z = 0 in the
world.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from typing import Any

from bt_manip.bim.ifc_input import IfcSource, check_count
from bt_manip.bim.shapes import (
    Box,
    ShapeReader,
    UnsupportedGeometry,
    footprint_box,
    is_box_like,
    placement_yaw,
)
from bt_manip.errors import Problem

PASSAGE_HEIGHT = 1.5
"""An opening from the floor at least this high (m) is a passage for the robot."""
FLOOR_TOLERANCE = 0.05
"""An opening or wall within this height (m) of the floor starts at the floor."""
MAX_WALLS = 5000
MAX_OPENINGS = 10000
MAX_SPACES = 2000
MAX_FURNITURE = 5000
MAX_SLABS = 2000


@dataclass
class Opening:
    """An opening in a wall: from ``start`` to ``end`` along the wall (m), ``bottom``..``top``
    above the floor; ``passage`` when the robot can go through it."""

    start: float
    end: float
    bottom: float
    top: float
    passage: bool
    kind: str
    """door, window or opening (unfilled)"""
    entity: Any

    @property
    def width(self) -> float:
        return self.end - self.start


@dataclass
class Wall:
    """A straight wall from ``start`` to ``end`` (its centre line, m) with its openings."""

    entity: Any
    name: str
    start: tuple[float, float]
    end: tuple[float, float]
    thickness: float
    bottom: float
    top: float
    openings: list[Opening] = field(default_factory=list)

    @property
    def length(self) -> float:
        return math.dist(self.start, self.end)

    def point_at(self, s: float) -> tuple[float, float]:
        t = s / self.length
        return (
            self.start[0] + t * (self.end[0] - self.start[0]),
            self.start[1] + t * (self.end[1] - self.start[1]),
        )


@dataclass
class Space:
    """A named space: its box (metres, floor at z = 0)."""

    entity: Any
    name: str
    key: str
    """The name as a world pose name."""
    box: Box


@dataclass
class Furniture:
    entity: Any
    name: str
    box: Box


@dataclass
class Building:
    """What one storey holds, in metres with the storey's floor at z = 0."""

    storey: Any
    floor_z: float
    extent: tuple[float, float, float, float]
    """(xmin, ymin, xmax, ymax) of the slabs (of the walls when there is no slab)."""
    walls: list[Wall] = field(default_factory=list)
    raised: list[Furniture] = field(default_factory=list)
    """Walls that do not stand on the floor, kept as static boxes."""
    spaces: list[Space] = field(default_factory=list)
    furniture: list[Furniture] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)


class Names:
    """Unique world names made from IFC names (letters, digits and underscores)."""

    def __init__(self) -> None:
        self.used: set[str] = set()

    def make(self, name: str | None, fallback: str) -> str:
        base = re.sub(r"[^A-Za-z0-9_]+", "_", name or "").strip("_").lower() or fallback
        out, n = base, 2
        while out in self.used:
            out, n = f"{base}_{n}", n + 1
        self.used.add(out)
        return out


def choose_storey(source: IfcSource) -> Any:
    """The storey to build: the one holding the most walls. A file without one is a problem."""
    storeys = source.model.by_type("IfcBuildingStorey")
    if not storeys:
        message = "no IfcBuildingStorey: the world is built from the walls of one storey"
        projects = source.model.by_type("IfcProject")
        if projects:
            source.fail(projects[0], message)
        else:
            source.problems.append(Problem(str(source.path), None, message))
        source.raise_problems()
    if len(storeys) == 1:
        return storeys[0]
    counts = {s.id(): 0 for s in storeys}
    for wall in source.model.by_type("IfcWall"):
        storey = storey_of(wall)
        if storey is not None and storey.id() in counts:
            counts[storey.id()] += 1
    return max(storeys, key=lambda s: (counts[s.id()], -s.id()))


def storey_of(element: Any) -> Any:
    """The IfcBuildingStorey containing ``element`` (through spaces), or None."""
    import ifcopenshell.util.element as util

    current = util.get_container(element) or util.get_aggregate(element)
    for _ in range(16):
        if current is None or current.is_a("IfcBuildingStorey"):
            return current
        current = util.get_container(current) or util.get_aggregate(current)
    return None


def storey_elevation(source: IfcSource, storey: Any) -> float:
    """Height (m) of the storey's floor: its placement, else its Elevation attribute."""
    import ifcopenshell.util.placement as placement

    if storey.ObjectPlacement is not None:
        return float(placement.get_local_placement(storey.ObjectPlacement)[2][3]) * source.scale
    return float(storey.Elevation or 0.0) * source.scale


def read_building(source: IfcSource, storey: Any, exclude: set[int], names: Names) -> Building:
    """The walls, spaces, furniture and extent of ``storey``; elements in ``exclude`` (step
    ids of the elements to install) are left out. Problems are collected in ``source``."""
    model = source.model
    single = len(model.by_type("IfcBuildingStorey")) == 1

    def on_storey(el: Any) -> bool:
        if single:
            return True
        s = storey_of(el)
        return s is not None and s.id() == storey.id()

    reader = ShapeReader(source.scale)
    floor_z = storey_elevation(source, storey)
    walls_found = [w for w in model.by_type("IfcWall") if w.id() not in exclude]
    check_count(source, "IfcWall", walls_found, MAX_WALLS)
    check_count(source, "IfcOpeningElement", model.by_type("IfcOpeningElement"), MAX_OPENINGS)
    spaces_found = model.by_type("IfcSpace")
    check_count(source, "IfcSpace", spaces_found, MAX_SPACES)
    furniture_found = model.by_type("IfcFurnishingElement")
    check_count(source, "IfcFurnishingElement", furniture_found, MAX_FURNITURE)
    slabs_found = model.by_type("IfcSlab")
    check_count(source, "IfcSlab", slabs_found, MAX_SLABS)
    out = Building(storey, floor_z, (0.0, 0.0, 0.0, 0.0))
    xs: list[float] = []
    ys: list[float] = []
    for wall in walls_found:
        if not on_storey(wall):
            continue
        box = _box_of(source, reader, wall, floor_z, need_box=True)
        if box is None:
            continue
        name = names.make(wall.Name, f"wall_{wall.id()}")
        if box.top <= FLOOR_TOLERANCE:
            out.notes.append(f"#{wall.id()} {wall.Name or ''}: below the floor, left out")
            continue
        if box.bottom > FLOOR_TOLERANCE:
            out.raised.append(Furniture(wall, name, box))
            continue
        c, s = box.axis()
        half = box.size[0] / 2
        start = (box.centre[0] - c * half, box.centre[1] - s * half)
        end = (box.centre[0] + c * half, box.centre[1] + s * half)
        w = Wall(wall, name, start, end, box.size[1], max(box.bottom, 0.0), box.top)
        w.openings = _openings(source, reader, w, floor_z)
        out.walls.append(w)
        xs += [start[0], end[0]]
        ys += [start[1], end[1]]
    slab_xy: list[tuple[float, float, float, float]] = []
    for slab in slabs_found:
        if slab.id() in exclude or not on_storey(slab):
            continue
        box = _box_of(source, reader, slab, floor_z, need_box=False)
        if box is not None:
            slab_xy.append(_xy_bounds(box))
    for space in spaces_found:
        if not on_storey(space):
            continue
        try:
            solid = reader.solid(space)
        except UnsupportedGeometry as exc:
            out.notes.append(f"#{space.id()} IfcSpace '{space.Name or ''}' left out: {exc}")
            continue
        box = _shift(footprint_box(solid.points, placement_yaw(space)), floor_z)
        label = space.LongName if getattr(space, "LongName", None) else space.Name
        out.spaces.append(Space(space, label or f"space {space.id()}", "", box))
    for item in furniture_found:
        if item.id() in exclude or not on_storey(item):
            continue
        box = _box_of(source, reader, item, floor_z, need_box=False)
        if box is not None:
            out.furniture.append(
                Furniture(item, names.make(item.Name, f"furniture_{item.id()}"), box)
            )
    if slab_xy:
        out.extent = (
            min(b[0] for b in slab_xy),
            min(b[1] for b in slab_xy),
            max(b[2] for b in slab_xy),
            max(b[3] for b in slab_xy),
        )
    elif xs:
        out.extent = (min(xs), min(ys), max(xs), max(ys))
    return out


def _xy_bounds(box: Box) -> tuple[float, float, float, float]:
    c, s = box.axis()
    hx, hy = box.size[0] / 2, box.size[1] / 2
    ex = abs(c) * hx + abs(s) * hy
    ey = abs(s) * hx + abs(c) * hy
    return (box.centre[0] - ex, box.centre[1] - ey, box.centre[0] + ex, box.centre[1] + ey)


def _shift(box: Box, floor_z: float) -> Box:
    x, y, z = box.centre
    return Box((x, y, z - floor_z), box.size, box.yaw)


def _box_of(
    source: IfcSource, reader: ShapeReader, element: Any, floor_z: float, need_box: bool
) -> Box | None:
    """The element's upright box (floor at z = 0); a problem when it cannot be read, or when
    ``need_box`` and the body is not box-like."""
    try:
        solid = reader.solid(element)
    except UnsupportedGeometry as exc:
        source.fail(element, f"unsupported geometry: {exc}")
        return None
    box = footprint_box(solid.points, placement_yaw(element))
    if need_box and not is_box_like(solid, box):
        fill = solid.volume / box.volume if box.volume > 0 else 0.0
        source.fail(
            element,
            f"unsupported geometry: its body fills {fill:.0%} of its upright bounding box "
            f"({box.size[0]:.3f} x {box.size[1]:.3f} x {box.size[2]:.3f} m); a straight, "
            "upright element of constant thickness is expected (curved, L-shaped, sloped or "
            "tilted ones are not read)",
        )
        return None
    return _shift(box, floor_z)


def _openings(source: IfcSource, reader: ShapeReader, wall: Wall, floor_z: float) -> list[Opening]:
    """The wall's openings along its centre line, overlapping ones merged."""
    ux = (wall.end[0] - wall.start[0]) / wall.length
    uy = (wall.end[1] - wall.start[1]) / wall.length
    found: list[Opening] = []
    for rel in getattr(wall.entity, "HasOpenings", None) or []:
        opening = rel.RelatedOpeningElement
        try:
            solid = reader.solid(opening)
        except UnsupportedGeometry as exc:
            source.fail(opening, f"unsupported geometry: {exc}")
            continue
        pts = solid.points
        along = (pts[:, 0] - wall.start[0]) * ux + (pts[:, 1] - wall.start[1]) * uy
        start = max(float(along.min()), 0.0)
        end = min(float(along.max()), wall.length)
        if end - start < 0.01:
            continue
        bottom = float(pts[:, 2].min()) - floor_z
        top = float(pts[:, 2].max()) - floor_z
        kind = "opening"
        for fill in getattr(opening, "HasFillings", None) or []:
            filler = fill.RelatedBuildingElement
            if filler.is_a("IfcDoor"):
                kind = "door"
            elif filler.is_a("IfcWindow"):
                kind = "window"
        passage = bottom <= wall.bottom + FLOOR_TOLERANCE and top >= min(
            PASSAGE_HEIGHT, wall.top - FLOOR_TOLERANCE
        )
        found.append(Opening(start, end, max(bottom, wall.bottom), min(top, wall.top), passage,
                             kind, opening))
    found.sort(key=lambda o: o.start)
    merged: list[Opening] = []
    for o in found:
        if merged and o.start <= merged[-1].end:
            m = merged[-1]
            m.end = max(m.end, o.end)
            m.bottom = min(m.bottom, o.bottom)
            m.top = max(m.top, o.top)
            m.passage = m.passage or o.passage
            if o.kind == "door":
                m.kind = "door"
        else:
            merged.append(o)
    return merged
