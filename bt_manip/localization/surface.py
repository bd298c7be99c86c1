"""A likelihood field measured from the obstacles' faces, for a laser mounted off the base's
centre.

The plain field (:meth:`~bt_manip.localization.likelihood_field.LikelihoodField.from_grid`)
gives distance 0 anywhere inside an occupied cell, and the occupancy grid marks every cell a
shape overlaps, so obstacles grow by up to a cell: a beam that ends a little inside a wall (the
pose placed too close to what the laser faces) scores as well as one that ends on its face.
With a laser that looks mostly one way (the Husky's 270 deg at the front) that pulls the
estimate towards what the laser faces by about half a cell.

:func:`surface_field` measures distances from the faces themselves: points sampled along every
outline of the map's bodies (:func:`~bt_manip.localization.map_from_world.static_outlines`),
each marking the cell it lies in, so a face lies anywhere within its cells, on average at their
centres. Faces buried in another body (two walls meeting) are left out. Particles of a global
localisation still go only to the grid's free cells.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from bt_manip.localization.likelihood_field import LikelihoodField
from bt_manip.navigation.grid import OccupancyGrid
from bt_manip.navigation.shapes import Disc, Outline

SAMPLES_PER_CELL = 4
"""Points sampled along a face per cell length."""
MAX_FACE_POINTS = 5_000_000
"""Most points sampled over all faces (a bound on the work for a huge map)."""


def face_points(outlines: list[Outline], spacing: float) -> np.ndarray:
    """Points (n, 2) every ``spacing`` metres or closer along the boundary of each outline."""
    chunks = []
    total = 0
    for outline in outlines:
        if isinstance(outline, Disc):
            n = max(16, math.ceil(2.0 * math.pi * outline.radius / spacing))
            a = np.arange(n) * (2.0 * math.pi / n)
            chunks.append(np.column_stack([outline.cx + outline.radius * np.cos(a),
                                           outline.cy + outline.radius * np.sin(a)]))
            total += n
            continue
        v = np.asarray(outline.vertices, dtype=float)
        for a, b in zip(v, np.roll(v, -1, axis=0), strict=True):
            k = max(1, math.ceil(float(np.hypot(*(b - a))) / spacing))
            t = np.arange(k)[:, None] / k
            chunks.append(a + t * (b - a))
            total += k
        if total > MAX_FACE_POINTS:
            raise ValueError(f"the map's outlines need more than {MAX_FACE_POINTS:,} face "
                             "points")
    return np.concatenate(chunks) if chunks else np.zeros((0, 2))


def surface_field(grid: OccupancyGrid, outlines: list[Outline],
                  max_dist: float) -> LikelihoodField:
    """The likelihood field of ``grid`` with distances to the faces of ``outlines`` (see the
    module docstring); the free cells are ``grid``'s."""
    occ = np.asarray(grid.occupied, dtype=bool)
    rows, cols = occ.shape
    res = grid.resolution
    pts = face_points(outlines, res / SAMPLES_PER_CELL)
    col = np.floor((pts[:, 0] - grid.origin[0]) / res).astype(np.int64)
    row = np.floor((pts[:, 1] - grid.origin[1]) / res).astype(np.int64)
    on_map = (col >= 0) & (col < cols) & (row >= 0) & (row < rows)
    row, col = row[on_map], col[on_map]
    # a cell all of whose neighbours are occupied is inside the union of the bodies
    pad = np.pad(occ, 1, constant_values=False)
    buried = pad[:-2, 1:-1] & pad[2:, 1:-1] & pad[1:-1, :-2] & pad[1:-1, 2:] & occ
    faces = np.zeros_like(occ)
    keep = ~buried[row, col]
    faces[row[keep], col[keep]] = True
    field_ = LikelihoodField.from_grid(dataclasses.replace(grid, occupied=faces), max_dist)
    free = np.flatnonzero(~occ).astype(field_.free.dtype)
    free.flags.writeable = False
    return dataclasses.replace(field_, free=free)
