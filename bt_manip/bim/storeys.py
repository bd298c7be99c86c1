"""Which storey of the building becomes the world.

``--storey NAME|INDEX`` names it (a storey's name first; else an index, 0-based, in ascending
elevation); by default it is the ground storey: the elevation nearest 0, ties broken by the
most walls, then by the file's order. :class:`StoreyChoice` says which one and why, and lists
them all for the printed summary.

A file without any IfcBuildingStorey (its elements contained in the IfcBuilding or the IfcSite
directly, as small exports and IFC4.3 sample files often are) is read whole, as one level:
its IfcBuilding stands for the storey (else its IfcSite, else its IfcProject), at the height of
that entity's placement.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from bt_manip.bim.ifc_input import IfcSource
from bt_manip.bim.shapes import ShapeReader, UnsupportedGeometry
from bt_manip.errors import InputError

ELEVATION_TIE = 0.01
"""Storeys whose elevations (m) differ by less than this are at the same level."""


@dataclass(frozen=True)
class StoreyChoice:
    """The storey chosen, why, and every storey in ascending elevation (name, elevation)."""

    storey: Any
    elevation: float
    reason: str
    storeys: tuple[tuple[str, float], ...]

    @property
    def name(self) -> str:
        return str(self.storey.Name or f"#{self.storey.id()}")

    def text(self) -> str:
        """``storey 'Level 1' (elevation 0.00 m, the ground storey; others: ...)``, or for a
        file without storeys ``level 'Building' (IfcBuilding, elevation 0.00 m: ...)``."""
        if not self.storeys:
            return (f"level '{self.name}' ({self.storey.is_a()}, elevation "
                    f"{self.elevation:.2f} m: {self.reason})")
        listed = ", ".join(f"{i} '{n}' {z:.2f} m" for i, (n, z) in enumerate(self.storeys))
        return (f"storey '{self.name}' (elevation {self.elevation:.2f} m, {self.reason}; "
                f"storeys by elevation: {listed})")


def storey_of(element: Any, memo: dict[tuple[str, int], Any] | None = None,
              contained: dict[int, Any] | None = None) -> Any:
    """The IfcBuildingStorey containing ``element`` (through spaces and aggregates), or None.

    With ``memo`` (one dict per file), the storey found above each container, and the
    container found above each element (ifcopenshell.util.element's ``get_container``, which
    climbs an aggregated part's wholes to the first contained one), are kept: the elements of
    a storey share their containers and wholes, so each climb is made once.
    ``contained`` (:func:`direct_containers`) gives the containers of the elements directly
    contained in one."""
    import ifcopenshell.util.element as util

    key = int(element.id())
    if contained is not None and key in contained:
        current = contained[key] or util.get_aggregate(element)
    else:
        current = _container(element, memo) or util.get_aggregate(element)
    if memo is None or current is None:
        return _climb(current, memo)
    key = int(current.id())
    if ("storey", key) not in memo:
        memo["storey", key] = _climb(current, memo)
    return memo["storey", key]


MAX_CLIMB = 16
"""Containers and aggregates climbed at most from an element to its storey."""


def _container(element: Any, memo: dict[tuple[str, int], Any] | None) -> Any:
    """ifcopenshell.util.element's ``get_container(element)`` (the first container of the
    element or of its parents: aggregates, nests, fills, voids), each element's answer kept in
    ``memo``; None after :data:`MAX_CLIMB` parents (a loop of parents in a broken file)."""
    import ifcopenshell.util.element as util

    if memo is None:
        return util.get_container(element)
    path: list[int] = []
    found = None
    current = element
    for _ in range(MAX_CLIMB):
        key = int(current.id())
        if ("container", key) in memo:
            found = memo["container", key]
            break
        path.append(key)
        rels = getattr(current, "ContainedInStructure", None)
        if rels:
            found = rels[0].RelatingStructure
            break
        current = util.get_parent(current)
        if current is None:
            break
    for key in path:
        memo["container", key] = found
    return found


def direct_containers(model: Any) -> dict[int, Any]:
    """The spatial container of each element contained in exactly one
    (IfcRelContainedInSpatialStructure), by step id: read in one pass over the relations
    rather than element by element."""
    found: dict[int, Any] = {}
    twice: set[int] = set()
    for rel in model.by_type("IfcRelContainedInSpatialStructure"):
        structure = rel.RelatingStructure
        for el in rel.RelatedElements or ():
            key = int(el.id())
            if key in found:
                twice.add(key)
            found[key] = structure
    for key in twice:  # in several: the element's own first relation decides
        del found[key]
    return found


def _climb(current: Any, memo: dict[tuple[str, int], Any] | None = None) -> Any:
    """The first storey from ``current`` up its containers and aggregates (16 steps at most)."""
    import ifcopenshell.util.element as util

    for _ in range(MAX_CLIMB):
        if current is None or current.is_a("IfcBuildingStorey"):
            return current
        current = _container(current, memo) or util.get_aggregate(current)
    return None


def one_level(model: Any) -> bool:
    """Whether every element of the file is on the level built: it has one storey, or none
    (read whole, see the module)."""
    return len(model.by_type("IfcBuildingStorey")) <= 1


def storey_origin(source: IfcSource, storey: Any) -> tuple[float, float, float] | None:
    """Where (m) the storey's local placement puts its origin (each storey's once per
    source); None without one. A placement that cannot be read (a loop) is the storey's
    problem, raised."""
    key = int(storey.id())
    if key not in source.origins:
        at = getattr(storey, "ObjectPlacement", None)
        found = None
        if at is not None and at.is_a("IfcLocalPlacement"):
            try:
                matrix = ShapeReader(source.scale).placement(at)
            except UnsupportedGeometry as exc:
                raise InputError([source.problem(
                    storey, f"its elevation cannot be read: {exc}")]) from None
            x, y, z = (float(v) * source.scale for v in matrix[:3, 3])
            found = (x, y, z)
        source.origins[key] = found
    return source.origins[key]


def storey_elevation(source: IfcSource, storey: Any) -> float:
    """Height (m) of the storey's floor: its placement (:func:`storey_origin`), else its
    Elevation attribute; for the building, site or project standing for the level of a file
    without storeys, its placement's height, else 0."""
    origin = storey_origin(source, storey)
    if origin is not None:
        return origin[2]
    return float(getattr(storey, "Elevation", None) or 0.0) * source.scale


def choose_storey(source: IfcSource, wanted: str | None = None) -> StoreyChoice:
    """The storey to build (see the module docstring). A ``wanted`` storey that matches none
    is a problem, and so is a file with neither a storey nor a building, site or project."""
    storeys = source.model.by_type("IfcBuildingStorey")
    if not storeys:
        return _whole_file(source, wanted)
    levels = {s.id(): storey_elevation(source, s) for s in storeys}
    ordered = sorted(storeys, key=lambda s: (levels[s.id()], s.id()))
    listing = tuple((str(s.Name or f"#{s.id()}"), levels[s.id()]) for s in ordered)
    if wanted is not None:
        named = [s for s in ordered if (s.Name or "") == wanted]
        named = named or [s for s in ordered if (s.Name or "").lower() == wanted.lower()]
        if named:
            return StoreyChoice(named[0], levels[named[0].id()], "given with --storey", listing)
        if wanted.strip().isdigit() and int(wanted) < len(ordered):
            s = ordered[int(wanted)]
            return StoreyChoice(s, levels[s.id()], f"index {int(wanted)} of --storey", listing)
        known = ", ".join(f"{i} '{n}'" for i, (n, _) in enumerate(listing))
        raise InputError.single("--storey", None,
                                f"no storey named or numbered '{wanted}'; storeys: {known}")
    if len(storeys) == 1:
        return StoreyChoice(storeys[0], levels[storeys[0].id()], "the only storey", listing)
    nearest = min(abs(z) for z in levels.values())
    ground = [s for s in storeys if abs(levels[s.id()]) - nearest < ELEVATION_TIE]
    if len(ground) == 1:
        return StoreyChoice(ground[0], levels[ground[0].id()],
                            "the ground storey: elevation nearest 0", listing)
    counts = {s.id(): 0 for s in ground}
    for wall in source.model.by_type("IfcWall"):
        storey = storey_of(wall)
        if storey is not None and storey.id() in counts:
            counts[storey.id()] += 1
    best = max(ground, key=lambda s: (counts[s.id()], -s.id()))
    return StoreyChoice(best, levels[best.id()], "the one holding the most walls", listing)


WHOLE_FILE_CLASSES = ("IfcBuilding", "IfcSite", "IfcProject")
"""What stands for the level of a file without storeys: the first of these the file has."""


def _whole_file(source: IfcSource, wanted: str | None) -> StoreyChoice:
    """The level of a file without storeys: its first IfcBuilding (else IfcSite, else
    IfcProject) by step id, every element on it."""
    level = None
    for cls in WHOLE_FILE_CLASSES:
        found = source.model.by_type(cls)
        if found:
            level = min(found, key=lambda e: e.id())
            break
    if level is None:
        raise InputError.single(str(source.path), None,
                                "no IfcBuildingStorey, IfcBuilding, IfcSite or IfcProject: "
                                "nothing to build a world from")
    if wanted is not None:
        raise InputError.single(
            "--storey", None,
            f"the file has no IfcBuildingStorey: it is read whole, as one level ({level.is_a()} "
            f"'{level.Name or '#' + str(level.id())}'); leave --storey out",
        )
    return StoreyChoice(level, storey_elevation(source, level),
                        "no IfcBuildingStorey in the file: every element read, as one level", ())
