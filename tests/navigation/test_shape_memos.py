"""The planar hull and the cells drawn for an outline: what is computed fast or remembered is
exactly what the plain algorithms give, and a remembered drawing never leaks from one grid or
world into another."""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np
import pybullet as pb
import pytest

from bt_manip.navigation import grid as grid_module
from bt_manip.navigation.grid import OccupancyGrid, rasterise
from bt_manip.navigation.shapes import Disc, Polygon, convex_hull


def reference_hull(points: np.ndarray) -> np.ndarray:
    """Andrew's monotone chain written plainly (numpy's unique, a Python loop)."""
    pts = np.unique(np.round(np.asarray(points, dtype=float), 12), axis=0)
    if len(pts) <= 2:
        return pts

    def cross(o: np.ndarray, a: np.ndarray, b: np.ndarray) -> float:
        return float((a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]))

    lower: list[np.ndarray] = []
    for p in pts:
        while len(lower) >= 2 and cross(lower[-2], lower[-1], p) <= 0:
            lower.pop()
        lower.append(p)
    upper: list[np.ndarray] = []
    for p in pts[::-1]:
        while len(upper) >= 2 and cross(upper[-2], upper[-1], p) <= 0:
            upper.pop()
        upper.append(p)
    return np.array(lower[:-1] + upper[:-1])


def point_sets() -> Iterator[np.ndarray]:
    rng = np.random.default_rng(21)
    for n in (1, 2, 3, 4, 7, 40, 300):
        yield rng.normal(size=(n, 2))
    yield np.round(rng.normal(size=(200, 2)), 1)  # many duplicates
    yield np.array([[0.0, 0.0], [1.0, 1.0], [2.0, 2.0], [3.0, 3.0]])  # all on one line
    yield np.array([[-0.0, 1.0], [0.0, 1.0], [1.0, 0.0], [0.0, 0.0], [1.0, 1.0]])  # signed zeros
    grid = rng.integers(0, 5, size=(150, 2)).astype(float)
    c, s = np.cos(0.7), np.sin(0.7)
    yield grid @ np.array([[c, -s], [s, c]]).T + 3.0  # rows of collinear points, turned
    corners = rng.integers(-2, 3, size=(80, 3)).astype(float) * 0.1  # a mesh seen tilted
    q = np.array(pb.getMatrixFromQuaternion(pb.getQuaternionFromEuler((0.3, -0.2, 1.1))))
    yield (corners @ q.reshape(3, 3).T)[:, :2] + np.array([1.5, -0.5])


@pytest.mark.parametrize("points", list(point_sets()))
def test_hull_is_the_plain_monotone_chain_bit_for_bit(points: np.ndarray) -> None:
    expected = reference_hull(points)
    hull = convex_hull(points)
    assert hull.dtype == expected.dtype and hull.shape == expected.shape
    assert hull.tobytes() == expected.tobytes()


def test_hull_of_a_square_with_inner_and_edge_points_is_its_corners_anticlockwise() -> None:
    pts = np.array([[0, 0], [2, 0], [2, 2], [0, 2], [1, 1], [1, 0], [2, 1.5]], dtype=float)
    assert convex_hull(pts).tolist() == [[0, 0], [2, 0], [2, 2], [0, 2]]


@pytest.fixture()
def client() -> Iterator[int]:
    c = pb.connect(pb.DIRECT)
    yield c
    pb.disconnect(c)


def _scene(c: int, shift: float) -> list[int]:
    bodies = []
    for half, pos, yaw in [((0.5, 0.1, 0.5), (0.3 + shift, 0.2, 0.5), 0.0),
                           ((0.2, 0.2, 0.3), (1.2, 1.1 - shift, 0.3), 0.6)]:
        col = pb.createCollisionShape(pb.GEOM_BOX, halfExtents=half, physicsClientId=c)
        quat = pb.getQuaternionFromEuler((0, 0, yaw))
        bodies.append(pb.createMultiBody(0, col, -1, pos, quat, physicsClientId=c))
    col = pb.createCollisionShape(pb.GEOM_CYLINDER, radius=0.25, height=0.8, physicsClientId=c)
    bodies.append(pb.createMultiBody(0, col, -1, (-0.4, 1.3, 0.4), physicsClientId=c))
    return bodies


def test_remembered_drawings_match_fresh_ones_across_worlds_grids_and_bands(
    client: int, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Two scenes in one process (the second with moved bodies), several resolutions, extents
    and bands, with cells listed per body: every grid equals the grid drawn with an empty
    memory of drawings."""
    other = pb.connect(pb.DIRECT)
    try:
        scenes = [(client, _scene(client, 0.0)), (other, _scene(other, 0.13))]
        cases = [(res, ext, band, remember)
                 for res in (0.05, 0.037)
                 for ext in ((-1.0, -1.0, 3.0, 3.0), (-1.02, -0.98, 2.5, 3.1))
                 for band in ((0.02, 0.45), (0.02, 2.0))
                 for remember in (False, True)]
        grids = []
        for c, bodies in scenes * 2:  # the second round draws from memory
            for res, ext, band, remember in cases:
                grids.append(rasterise(c, bodies, resolution=res, band=band, extent=ext,
                                       remember=remember))
        assert len(grid_module._HIT_MEMO._blocks) > 0
        monkeypatch.setattr(grid_module, "_HIT_MEMO", grid_module._HitMemo())
        fresh = []
        for c, bodies in scenes:
            for res, ext, band, remember in cases:
                grid_module._HIT_MEMO.clear()
                fresh.append(rasterise(c, bodies, resolution=res, band=band, extent=ext,
                                       remember=remember))
        for got, want in zip(grids, fresh * 2, strict=True):
            assert np.array_equal(got.occupied, want.occupied)
            assert got.sources.keys() == want.sources.keys()
            for body, cells in want.sources.items():
                assert np.array_equal(got.sources[body], cells)
        # the two scenes differ, so a drawing of one was not taken for the other
        assert not np.array_equal(fresh[0].occupied, fresh[len(cases)].occupied)
    finally:
        pb.disconnect(other)


def test_remembered_cells_are_read_only_and_the_memory_is_bounded(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    memo = grid_module._HitMemo()
    monkeypatch.setattr(grid_module, "_HIT_MEMO", memo)
    monkeypatch.setattr(grid_module._HitMemo, "MAX_ENTRIES", 10)
    monkeypatch.setattr(grid_module._HitMemo, "MAX_CELLS", 2000)
    grid = OccupancyGrid.empty((0.0, 0.0, 10.0, 10.0))
    square = Polygon(np.array([[1.0, 1.0], [2.0, 1.0], [2.0, 2.0], [1.0, 2.0]]))
    grid.mark([square])
    (((_, _, hit),),) = memo._blocks.values()
    with pytest.raises(ValueError):
        hit[0, 0] = False
    assert int(grid.occupied.sum()) == 400  # 20 x 20 cells of 5 cm
    for i in range(30):
        grid.mark([Disc(5.0, 5.0, 0.1 + 0.05 * i)])
        assert len(memo._blocks) <= 10 and memo.cells <= 2000
    assert memo.cells == sum(h.size for blocks in memo._blocks.values() for _, _, h in blocks)
    big = grid.cells_of(Disc(5.0, 5.0, 4.0))  # more cells than the memory holds: not kept
    assert len(big) > 2000 and memo.cells <= 2000
