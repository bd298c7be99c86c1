"""The likelihood field measured from the obstacles' faces (bt_manip.localization.surface)."""

from __future__ import annotations

import numpy as np
import pytest

from bt_manip.localization.surface import face_points, surface_field
from bt_manip.navigation.grid import OccupancyGrid
from bt_manip.navigation.shapes import Disc, Polygon


def _block_grid() -> tuple[OccupancyGrid, Polygon]:
    """A 2 m x 1 m map, 10 cm cells, with a 0.6 m thick block from x = 0.8 to 1.4 m."""
    occ = np.zeros((10, 20), bool)
    occ[:, 8:14] = True
    block = Polygon(np.array([[0.8, 0.0], [1.4, 0.0], [1.4, 1.0], [0.8, 1.0]]))
    return OccupancyGrid((0.0, 0.0), 0.1, occ), block


def test_distances_grow_inside_a_body_from_its_faces() -> None:
    grid, block = _block_grid()
    field = surface_field(grid, [block], 2.0)
    row = 5
    d = field.distance[row + 1, 1:-1]  # the field has a border cell on each side
    assert d[8] == 0.0 and d[13] == 0.0  # the cells the faces run through
    assert d[10] == pytest.approx(0.2) and d[11] == pytest.approx(0.2)  # deep inside
    assert d[5] == pytest.approx(0.3)  # in front of the face, as the plain field has it
    # particles go only where the grid is free
    cols = field.free % 20
    assert not np.any((cols >= 8) & (cols < 14))
    assert field.free.size == 10 * 14


def test_face_points_are_spaced_along_every_outline() -> None:
    disc = face_points([Disc(0.0, 0.0, 0.5)], 0.05)
    assert np.allclose(np.hypot(disc[:, 0], disc[:, 1]), 0.5)
    assert len(disc) >= 2 * np.pi * 0.5 / 0.05
    triangle = face_points([Polygon(np.array([[0, 0], [1, 0], [1, 1.0]]))], 0.05)
    closed = np.vstack([triangle, triangle[:1]])
    assert np.hypot(*np.diff(closed, axis=0).T).max() <= 0.05 + 1e-9
