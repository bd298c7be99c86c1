"""Which storey of the building becomes the world.

``--storey NAME|INDEX`` names it (a storey's name first; else an index, 0-based, in ascending
elevation); by default it is the ground storey: the elevation nearest 0, ties broken by the
most walls, then by the file's order. :class:`StoreyChoice` says which one and why, and lists
them all for the printed summary.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from bt_manip.bim.ifc_input import IfcSource
from bt_manip.errors import InputError, Problem

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
        """``storey 'Level 1' (elevation 0.00 m, the ground storey; others: ...)``."""
        listed = ", ".join(f"{i} '{n}' {z:.2f} m" for i, (n, z) in enumerate(self.storeys))
        return (f"storey '{self.name}' (elevation {self.elevation:.2f} m, {self.reason}; "
                f"storeys by elevation: {listed})")


def storey_of(element: Any, memo: dict[int, Any] | None = None,
              contained: dict[int, Any] | None = None) -> Any:
    """The IfcBuildingStorey containing ``element`` (through spaces and aggregates), or None.

    With ``memo`` (one dict per file), the storey found above each container is kept: the
    elements of a storey share their containers, so the climb is made once per container.
    ``contained`` (:func:`direct_containers`) gives the containers of the elements directly
    contained in one."""
    import ifcopenshell.util.element as util

    key = int(element.id())
    if contained is not None and key in contained:
        current = contained[key] or util.get_aggregate(element)
    else:
        current = util.get_container(element) or util.get_aggregate(element)
    if memo is None or current is None:
        return _climb(current)
    key = int(current.id())
    if key not in memo:
        memo[key] = _climb(current)
    return memo[key]


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


def _climb(current: Any) -> Any:
    """The first storey from ``current`` up its containers and aggregates (16 steps at most)."""
    import ifcopenshell.util.element as util

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


def choose_storey(source: IfcSource, wanted: str | None = None) -> StoreyChoice:
    """The storey to build (see the module docstring). A file without one is a problem, and
    so is a ``wanted`` storey that matches none."""
    storeys = source.model.by_type("IfcBuildingStorey")
    if not storeys:
        message = "no IfcBuildingStorey: the world is built from the walls of one storey"
        projects = source.model.by_type("IfcProject")
        if projects:
            source.fail(projects[0], message)
        else:
            source.problems.append(Problem(str(source.path), None, message))
        source.raise_problems()
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
