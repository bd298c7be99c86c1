"""The map a localisation filter works on: the world's static geometry as an occupancy grid.

A mapping run would have seen the walls and the furniture that the world file lists, not the
movable objects and not what is added while the world runs (a crate spawned by a tree). So
:func:`static_bodies` takes the bodies the world built from its file's ``walls`` and
``furniture`` sections, and :func:`map_from_world` rasterises them with the navigation grid's
own code (:func:`bt_manip.navigation.grid.rasterise`) in the height band a planar LiDAR sweeps.
:func:`static_outlines` gives the same bodies' outlines in that band (polygons and discs), for
whoever needs the exact geometry (a simulated scanner, a test).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from bt_manip.navigation.grid import DEFAULT_RESOLUTION, OccupancyGrid, rasterise
from bt_manip.navigation.shapes import Outline, ZBand, body_outlines

if TYPE_CHECKING:
    from bt_manip.sim.world import World

SCAN_BAND: ZBand = (0.05, 0.6)
"""Heights (m) a base-mounted planar LiDAR's map is cut at unless told otherwise: what stands in
this band is a wall to the scanner."""


def static_bodies(world: World) -> list[int]:
    """Body ids of the walls and furniture the world built from its file, in file order."""
    listed = {w.name for w in world.spec.walls} | {f.name for f in world.spec.furniture}
    return [
        info.body_id
        for info in world.infos.values()
        if info.kind in ("wall", "furniture") and info.name in listed
    ]


def map_from_world(
    world: World,
    *,
    resolution: float = DEFAULT_RESOLUTION,
    band: ZBand = SCAN_BAND,
    pad: float = 0.5,
) -> OccupancyGrid:
    """Occupancy grid of the world's static geometry (:func:`static_bodies`) in ``band``,
    covering its extent plus ``pad`` metres. Raises
    :class:`~bt_manip.navigation.grid.GridTooLarge` for a world too large to map."""
    bodies = static_bodies(world)
    if not bodies:
        raise ValueError(f"{world.path.name}: no walls or furniture to build a map from")
    return rasterise(world.client, bodies, resolution=resolution, band=band, pad=pad,
                     remember=False)


def static_outlines(world: World, band: ZBand = SCAN_BAND) -> list[Outline]:
    """Outlines (world frame) of the world's static geometry in ``band``."""
    out: list[Outline] = []
    for body in static_bodies(world):
        out += body_outlines(world.client, body, band)
    return out
