"""The building of one storey: walls with their openings, spaces, furniture and floor extent.

Walls come from IfcWall (and its subtypes, IfcWallStandardCase included) as straight segments
along the long side of their box, with the openings that void them (IfcRelVoidsElement), filled
or not by an IfcDoor or IfcWindow (IfcRelFillsElement). An opening is a passage for the robot
when it starts at the floor and reaches :data:`PASSAGE_HEIGHT` (or the top of a lower wall);
any other opening (a window, a hatch) cuts the wall but leaves a sill below it and a lintel
above it as static boxes, so the robot cannot drive through. Spaces (IfcSpace) become named
poses, and slabs (IfcSlab) give the floor's extent. Elevations are measured from the storey's
placement, which is z = 0 in the world.

Only what stands in the robot's height band (from the floor to ``band_top``: the top of the
tucked robot or of an element it carries, whichever is higher) matters to it; an element lying
entirely above it (a gable piece, a beam under the ceiling) is left out, and so is an element
whose body cannot be read (none, or one the geometry kernel refuses): each is listed in the
building's ``skipped`` with its reason, never a refusal of the building. A wall that is not a
plain box is read as the obstacle it is: a straight one with holes cut into its body gets those
holes as openings (:func:`~bt_manip.bim.footprints.wall_gaps`), any other becomes its footprint
(:func:`~bt_manip.bim.footprints.hull_boxes`). Curtain walls (IfcCurtainWall: its body, else its
plates and members), columns, stairs, ramps, railings, beams, coverings (but floor and ceiling
finishes), proxies, plates and members, lifts (IfcTransportElement) and the building services
that stand in rooms (:data:`SERVICE_CLASSES`: a bathtub, a radiator, a boiler) become obstacles
of their footprint, furniture (IfcFurnishingElement) too.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from typing import Any

from bt_manip.bim.floor_grid import MARGIN
from bt_manip.bim.footprints import strip_boxes, wall_gaps
from bt_manip.bim.ifc_input import IfcSource, check_count
from bt_manip.bim.shapes import (
    Box,
    ShapeReader,
    UnsupportedGeometry,
    footprint_box,
    hull_box,
    hull_xy,
    is_box_like,
)
from bt_manip.bim.storeys import (
    choose_storey,
    direct_containers,
    one_level,
    storey_elevation,
    storey_of,
)

__all__ = ["Building", "Furniture", "Names", "Opening", "Space", "Wall", "choose_storey",
           "read_building", "storey_elevation", "storey_of"]

PASSAGE_HEIGHT = 1.5
"""An opening from the floor at least this high (m) is a passage for the robot."""
FLOOR_TOLERANCE = 0.05
"""An opening or wall within this height (m) of the floor starts at the floor."""
RAISED_FLOOR = 0.6
"""When every door of the storey starts higher than the storey's elevation, by at most this
much (m), the doors stand on a finished floor laid on the structure the walls start from: they
are passages from there."""
MAX_WALLS = 5000
MAX_OPENINGS = 10000
MAX_SPACES = 2000
MAX_FURNITURE = 5000
MAX_SLABS = 2000
SERVICE_CLASSES = ("IfcFlowTerminal", "IfcEnergyConversionDevice", "IfcFlowStorageDevice",
                   "IfcFlowMovingDevice", "IfcFlowTreatmentDevice")
"""Building services that stand in rooms: sanitary terminals (a bathtub, a toilet), appliances,
radiators, boilers, tanks, pumps. Pipes, ducts, their fittings and valves (IfcFlowSegment,
IfcFlowFitting, IfcFlowController), thousands in a services model and mostly under ceilings,
are not read."""
MAX_OBSTACLES = 20000
"""Obstacles of the other classes (columns, stairs, proxies...) and curtain wall parts at most."""
OBSTACLE_CLASSES = ("IfcColumn", "IfcStair", "IfcStairFlight", "IfcRamp", "IfcRampFlight",
                    "IfcRailing", "IfcBeam", "IfcCovering", "IfcBuildingElementProxy",
                    "IfcPlate", "IfcMember", "IfcTransportElement", *SERVICE_CLASSES)
"""Classes read as obstacles besides walls, curtain walls and furniture."""
FINISHES = ("FLOORING", "CEILING", "ROOFING")
"""Covering types that are no obstacle: the robot drives on a floor finish."""


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
    """A static obstacle: its bounding box, and the boxes it is made of (``parts``, world frame;
    empty: the box itself)."""

    entity: Any
    name: str
    box: Box
    parts: list[Box] = field(default_factory=list)
    kind: str = "furniture"
    """furniture, raised wall, wall, curtain wall or obstacle"""

    @property
    def boxes(self) -> list[Box]:
        return self.parts or [self.box]


@dataclass
class Building:
    """What one storey holds, in metres with the storey's floor at z = 0."""

    storey: Any
    floor_z: float
    extent: tuple[float, float, float, float]
    """(xmin, ymin, xmax, ymax) of the slabs that reach within the floor grid's margin of
    the walls' lines (and of those lines too where they lie beyond that margin); of the walls
    alone when no slab does, of the other obstacles and furniture when there is no wall
    either."""
    walls: list[Wall] = field(default_factory=list)
    raised: list[Furniture] = field(default_factory=list)
    """Walls that do not stand on the floor, kept as static boxes."""
    spaces: list[Space] = field(default_factory=list)
    furniture: list[Furniture] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    curtain_walls: list[Furniture] = field(default_factory=list)
    """Curtain walls, their body or their plates and members, as obstacles."""
    obstacles: list[Furniture] = field(default_factory=list)
    """Columns, stairs, railings, beams, coverings, proxies... and walls that are no box."""
    band_top: float = 0.0
    counts: dict[str, int] = field(default_factory=dict)
    """Elements of the storey read, by kind (walls, curtain walls, plates, members, doors,
    windows, other obstacles)."""
    skipped: list[tuple[str, str]] = field(default_factory=list)
    """(element, reason) of what was left out."""

    def skip(self, element: Any, reason: str) -> None:
        label = f"#{element.id()} {element.is_a()}" + (f" '{element.Name}'" if element.Name
                                                      else "")
        self.skipped.append((label, reason))

    def read_text(self) -> str:
        """What was read, and what was left out, in one paragraph."""
        c = self.counts

        def n(key: str) -> str:  # "2 walls", "1 wall"
            count = c.get(key, 0)
            return f"{count} {key if count != 1 else key[:-1]}"

        text = (
            f"{n('walls')}, {n('curtain walls')} ({n('plates')}, {n('members')}), "
            f"{n('doors')}, {n('windows')}, {n('other obstacles')} of storey "
            f"'{self.storey.Name or '#' + str(self.storey.id())}'"
        )
        if self.skipped:
            groups: dict[str, list[str]] = {}
            for label, why in self.skipped:
                groups.setdefault(re.sub(r" \(from [^)]*\)|, the band ends at [0-9.]+ m", "",
                                         why), []).append(label)
            parts = []
            for why, labels in groups.items():
                named = ", ".join(labels) if len(labels) <= 3 else f"{len(labels)} elements"
                parts.append(f"{named} ({why})")
            text += "; skipped: " + "; ".join(parts)
        return text


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


def _by_type(model: Any, ifc_class: str) -> list[Any]:
    """Entities of ``ifc_class`` (and its subtypes); none when the schema has no such class."""
    try:
        return list(model.by_type(ifc_class))
    except RuntimeError:
        return []


def read_building(
    source: IfcSource, storey: Any, exclude: set[int], names: Names, band_top: float = 2.0
) -> Building:
    """The walls, obstacles, spaces, furniture and extent of ``storey``; elements in
    ``exclude`` (step ids of the elements to install) are left out, and so is anything above
    ``band_top`` (m above the floor). Problems are collected in ``source``."""
    model = source.model
    single = one_level(model)
    climbed: dict[tuple[str, int], Any] = {}
    contained = {} if single else direct_containers(model)

    def on_storey(el: Any) -> bool:
        if single:
            return True
        s = storey_of(el, climbed, contained)
        return s is not None and s.id() == storey.id()

    reader = ShapeReader(source.scale, model, source.shift)
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
    others = [el for cls in OBSTACLE_CLASSES for el in _by_type(model, cls)]
    curtains = _by_type(model, "IfcCurtainWall")
    check_count(source, "obstacle (column, stair, proxy...)", others + curtains, MAX_OBSTACLES)
    out = Building(storey, floor_z, (0.0, 0.0, 0.0, 0.0), band_top=band_top)
    counts = dict.fromkeys(("walls", "curtain walls", "plates", "members", "doors", "windows",
                            "other obstacles"), 0)
    xs: list[float] = []
    ys: list[float] = []
    for wall in walls_found:
        if not on_storey(wall):
            continue
        counts["walls"] += 1
        for w in _read_wall(source, reader, wall, out, names):
            out.walls.append(w)
            xs += [w.start[0], w.end[0]]
            ys += [w.start[1], w.end[1]]
    _doors_on_a_raised_floor(out)
    for cls, key in (("IfcDoor", "doors"), ("IfcWindow", "windows")):
        counts[key] = sum(1 for el in _by_type(model, cls) if on_storey(el))
    done: set[int] = set(exclude)
    for curtain in curtains:
        if curtain.id() in exclude or not on_storey(curtain):
            continue
        counts["curtain walls"] += 1
        done.add(curtain.id())
        parts = [p for rel in getattr(curtain, "IsDecomposedBy", None) or []
                 for p in rel.RelatedObjects]
        counts["plates"] += sum(1 for p in parts if p.is_a("IfcPlate"))
        counts["members"] += sum(1 for p in parts if p.is_a("IfcMember"))
        done.update(p.id() for p in parts)
        pieces = [curtain] if curtain.Representation is not None else parts
        if not pieces:
            out.skip(curtain, "no body geometry and no plates or members")
        for piece in pieces:
            if piece.id() in exclude:
                continue
            found = _obstacle(reader, piece, out, names, "curtain wall")
            if found is not None:
                out.curtain_walls.append(found)
    for el in others:
        if el.id() in done or not on_storey(el):
            continue
        done.add(el.id())
        counts["other obstacles"] += 1
        if el.is_a("IfcCovering") and str(getattr(el, "PredefinedType", "")) in FINISHES:
            out.skip(el, f"a {str(el.PredefinedType).lower()} finish, no obstacle")
            continue
        pieces = [el]
        if el.Representation is None:  # a stair or a ramp made of its parts
            pieces = [p for rel in getattr(el, "IsDecomposedBy", None) or []
                      for p in rel.RelatedObjects if p.id() not in done]
            done.update(p.id() for p in pieces)
            if not pieces:
                out.skip(el, "it has no body geometry (no 'Body' representation)")
        for piece in pieces:
            found = _obstacle(reader, piece, out, names, "obstacle")
            if found is not None:
                out.obstacles.append(found)
    slab_xy: list[tuple[float, float, float, float]] = []
    for slab in slabs_found:
        if slab.id() in exclude or not on_storey(slab):
            continue
        try:
            pts = reader.points(slab)
        except UnsupportedGeometry as exc:
            out.skip(slab, str(exc))
            continue
        slab_xy.append((float(pts[:, 0].min()), float(pts[:, 1].min()),
                        float(pts[:, 0].max()), float(pts[:, 1].max())))
    for space in spaces_found:
        if not on_storey(space):
            continue
        try:
            pts = reader.points(space)
        except UnsupportedGeometry as exc:
            out.notes.append(f"#{space.id()} IfcSpace '{space.Name or ''}' left out: {exc}")
            continue
        box = _shift(footprint_box(pts, reader.yaw(space)), floor_z)
        label = space.LongName if getattr(space, "LongName", None) else space.Name
        out.spaces.append(Space(space, label or f"space {space.id()}", "", box))
    for item in furniture_found:
        if item.id() in exclude or not on_storey(item):
            continue
        counts["other obstacles"] += 1
        found = _obstacle(reader, item, out, names, "furniture")
        if found is not None:
            out.furniture.append(found)
    out.counts = counts
    if xs:  # slabs away from every wall are not this floor (a survey marker at the origin)
        w0, v0, w1, v1 = min(xs), min(ys), max(xs), max(ys)
        slab_xy = [b for b in slab_xy if b[0] <= w1 + MARGIN and b[2] >= w0 - MARGIN
                   and b[1] <= v1 + MARGIN and b[3] >= v0 - MARGIN]
    if slab_xy:
        out.extent = (
            min(b[0] for b in slab_xy),
            min(b[1] for b in slab_xy),
            max(b[2] for b in slab_xy),
            max(b[3] for b in slab_xy),
        )
        x0, y0, x1, y1 = out.extent
        if xs and (min(xs) < x0 - MARGIN or max(xs) > x1 + MARGIN or min(ys) < y0 - MARGIN
                   or max(ys) > y1 + MARGIN):  # walls beyond the slabs' margin: theirs too
            out.extent = (min([*xs, x0]), min([*ys, y0]), max([*xs, x1]), max([*ys, y1]))
    elif xs:
        out.extent = (min(xs), min(ys), max(xs), max(ys))
    else:  # neither slabs nor walls (a row of columns): what stands on the floor
        corners = [c for f in out.curtain_walls + out.obstacles + out.furniture
                   for box in f.boxes for c in _corners(box)]
        if corners:
            out.extent = (min(c[0] for c in corners), min(c[1] for c in corners),
                          max(c[0] for c in corners), max(c[1] for c in corners))
    return out


def _corners(box: Box) -> list[tuple[float, float]]:
    """The four corners (x, y) of a box's footprint."""
    c, s = math.cos(box.yaw), math.sin(box.yaw)
    hx, hy = box.size[0] / 2, box.size[1] / 2
    return [(box.centre[0] + c * a - s * b, box.centre[1] + s * a + c * b)
            for a, b in ((-hx, -hy), (hx, -hy), (hx, hy), (-hx, hy))]


def _doors_on_a_raised_floor(building: Building) -> None:
    """Doors all starting a little above the walls' foot are passages (see RAISED_FLOOR)."""
    doors = [o for w in building.walls for o in w.openings if o.kind == "door"]
    if not doors or any(o.passage for o in doors):
        return
    floor = min(o.bottom - w.bottom for w in building.walls for o in w.openings
                if o.kind == "door")
    if not FLOOR_TOLERANCE < floor <= RAISED_FLOOR:
        return
    for w in building.walls:
        for o in w.openings:
            if o.bottom - w.bottom <= floor + FLOOR_TOLERANCE and o.top - w.bottom >= min(
                floor + PASSAGE_HEIGHT, w.top - w.bottom - FLOOR_TOLERANCE
            ):
                o.passage = True
    building.notes.append(f"the doors start {floor:.2f} m above the foot of the walls, on a "
                          "finished floor: they are passages from there")


def _shift(box: Box, floor_z: float) -> Box:
    x, y, z = box.centre
    return Box((x, y, z - floor_z), box.size, box.yaw)


def _obstacle(reader: ShapeReader, element: Any, building: Building, names: Names,
              kind: str) -> Furniture | None:
    """The element as an obstacle of its footprint, or None (skipped, with its reason)."""
    try:
        pts = reader.points(element)
    except UnsupportedGeometry as exc:
        building.skip(element, str(exc))
        return None
    return _footprint(pts, element, building, names, kind, reader.yaw(element))


def _footprint(pts: Any, element: Any, building: Building, names: Names,
               kind: str, yaw: float | None) -> Furniture | None:
    bottom = float(pts[:, 2].min()) - building.floor_z
    top = float(pts[:, 2].max()) - building.floor_z
    if top <= FLOOR_TOLERANCE:
        building.skip(element, "at or below the floor")
        return None
    if bottom >= building.band_top:
        building.skip(element, f"above the robot's height band, which ends at "
                               f"{building.band_top:.2f} m (from {bottom:.2f} m)")
        return None
    bottom = max(bottom, 0.0)
    corners = hull_xy(pts[:, :2])
    box = hull_box(corners, yaw)
    # the hull of the corners is the corners themselves, and their least box this one
    parts = [_shift(b, building.floor_z) for b in
             strip_boxes(corners, box, bottom + building.floor_z, top + building.floor_z)]
    fallback = {"furniture": "furniture", "curtain wall": "curtain", "raised wall": "wall"}
    name = names.make(element.Name, f"{fallback.get(kind, 'obstacle')}_{element.id()}")
    box = Box((box.centre[0], box.centre[1], (bottom + top) / 2), (box.size[0], box.size[1],
              top - bottom), box.yaw)
    return Furniture(element, name, box, parts if len(parts) > 1 else [], kind)


def _read_wall(source: IfcSource, reader: ShapeReader, wall: Any, building: Building,
               names: Names) -> list[Wall]:
    """The wall as a straight wall with its openings; a wall that is not one (raised, round,
    L-shaped) is added to the building's obstacles instead, and one that cannot be read or
    lies out of the band is skipped."""
    floor_z = building.floor_z
    try:
        solid = reader.solid(wall)
    except UnsupportedGeometry as exc:
        building.skip(wall, str(exc))
        return []
    box = _shift(footprint_box(solid.points, reader.yaw(wall)), floor_z)
    if box.top <= FLOOR_TOLERANCE:
        building.notes.append(f"#{wall.id()} {wall.Name or ''}: below the floor, left out")
        building.skip(wall, "below the floor")
        return []
    if box.bottom >= building.band_top:
        building.skip(wall, f"above the robot's height band, which ends at "
                            f"{building.band_top:.2f} m (from {box.bottom:.2f} m)")
        return []
    box_like = is_box_like(solid, box)
    if box.bottom > FLOOR_TOLERANCE:
        if box_like:
            name = names.make(wall.Name, f"wall_{wall.id()}")
            building.raised.append(Furniture(wall, name, box, [], "raised wall"))
        else:
            found = _footprint(solid.points, wall, building, names, "raised wall",
                               reader.yaw(wall))
            if found is not None:
                building.raised.append(found)
        return []
    gaps: list[tuple[float, float, float, float]] = []
    if not box_like:
        straight = box.size[0] >= 3 * box.size[1]
        if not straight:
            found = _footprint(solid.points, wall, building, names, "wall", reader.yaw(wall))
            if found is not None:
                building.obstacles.append(found)
            return []
        try:
            verts, faces = reader.mesh(wall)
        except UnsupportedGeometry as exc:
            building.skip(wall, str(exc))
            return []
        c, s = box.axis()
        half = box.size[0] / 2
        start = (box.centre[0] - c * half, box.centre[1] - s * half)
        shifted = verts - [0.0, 0.0, floor_z]
        gaps = wall_gaps(shifted, faces, start, box.yaw, box.size[0], max(box.bottom, 0.0),
                         box.top)
        # an uncovered part at the top of the body, wholly above the band, is where the wall's
        # top runs lower (sloped or stepped under a roof), not an opening: kept as one, it
        # would merge with the windows below it into a single opening the length of the wall
        gaps = [g for g in gaps
                if g[3] < box.top - FLOOR_TOLERANCE or g[2] < building.band_top]
    name = names.make(wall.Name, f"wall_{wall.id()}")
    c, s = box.axis()
    half = box.size[0] / 2
    start = (box.centre[0] - c * half, box.centre[1] - s * half)
    end = (box.centre[0] + c * half, box.centre[1] + s * half)
    w = Wall(wall, name, start, end, box.size[1], max(box.bottom, 0.0), box.top)
    holes = [_opening_of(w, a, b, lo, hi, "hole", None) for a, b, lo, hi in gaps]
    w.openings = _openings(source, reader, w, floor_z, building, holes)
    return [w]


def _opening_of(wall: Wall, start: float, end: float, bottom: float, top: float, kind: str,
                entity: Any) -> Opening:
    passage = bottom <= wall.bottom + FLOOR_TOLERANCE and top >= min(
        PASSAGE_HEIGHT, wall.top - FLOOR_TOLERANCE
    )
    return Opening(start, end, max(bottom, wall.bottom), min(top, wall.top), passage, kind,
                   entity)


def _openings(source: IfcSource, reader: ShapeReader, wall: Wall, floor_z: float,
              building: Building, holes: list[Opening]) -> list[Opening]:
    """The wall's openings along its centre line (its IfcOpeningElements and the holes of
    its body), overlapping ones merged."""
    ux = (wall.end[0] - wall.start[0]) / wall.length
    uy = (wall.end[1] - wall.start[1]) / wall.length
    found: list[Opening] = list(holes)
    for rel in getattr(wall.entity, "HasOpenings", None) or []:
        opening = rel.RelatedOpeningElement
        try:
            pts = reader.points(opening)
        except UnsupportedGeometry as exc:
            building.skip(opening, str(exc))
            continue
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
        found.append(_opening_of(wall, start, end, bottom, top, kind, opening))
    found.sort(key=lambda o: o.start)
    merged: list[Opening] = []
    for o in found:
        if merged and o.start <= merged[-1].end:
            m = merged[-1]
            m.end = max(m.end, o.end)
            m.bottom = min(m.bottom, o.bottom)
            m.top = max(m.top, o.top)
            m.passage = m.passage or o.passage
            if o.kind == "door" or m.kind == "hole":
                m.kind = o.kind
        else:
            merged.append(o)
    return merged
