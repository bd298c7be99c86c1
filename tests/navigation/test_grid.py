"""Occupancy grids from a hand-built PyBullet scene: cells checked exactly."""

from __future__ import annotations

import math
import zlib
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pybullet as pb
import pytest

from bt_manip.navigation.costmap import CostMap, InflationOptions, clearance, inflate
from bt_manip.navigation.grid import OccupancyGrid, rasterise, save_cost_png
from bt_manip.navigation.shapes import Disc, Polygon, body_outlines

EXTENT = (-1.0, -1.0, 3.0, 3.0)  # origin (-1, -1), 80 x 80 cells of 5 cm


@pytest.fixture()
def client() -> Iterator[int]:
    c = pb.connect(pb.DIRECT)
    yield c
    pb.disconnect(c)


def box(
    c: int, half: tuple[float, float, float], pos: tuple[float, float, float], yaw: float = 0.0
) -> int:
    col = pb.createCollisionShape(pb.GEOM_BOX, halfExtents=half, physicsClientId=c)
    quat = pb.getQuaternionFromEuler((0, 0, yaw))
    return pb.createMultiBody(0, col, -1, pos, quat, physicsClientId=c)


def cylinder(c: int, radius: float, height: float, pos: tuple[float, float, float]) -> int:
    col = pb.createCollisionShape(pb.GEOM_CYLINDER, radius=radius, height=height, physicsClientId=c)
    return pb.createMultiBody(0, col, -1, pos, physicsClientId=c)


def sphere(c: int, radius: float, pos: tuple[float, float, float]) -> int:
    col = pb.createCollisionShape(pb.GEOM_SPHERE, radius=radius, physicsClientId=c)
    return pb.createMultiBody(0, col, -1, pos, physicsClientId=c)


def cells(grid: OccupancyGrid, body: int) -> set[tuple[int, int]]:
    return {(int(r), int(c)) for r, c in grid.occupied_by(body)}


def block(r0: int, r1: int, c0: int, c1: int) -> set[tuple[int, int]]:
    return {(r, c) for r in range(r0, r1 + 1) for c in range(c0, c1 + 1)}


def test_axis_aligned_box_fills_exactly_its_cells(client: int) -> None:
    # x 0..1.0, y 0..0.5: cell borders fall on the box faces, so no spill-over
    b = box(client, (0.5, 0.25, 0.3), (0.5, 0.25, 0.3))
    grid = rasterise(client, [b], extent=EXTENT)
    assert grid.shape == (80, 80)
    assert cells(grid, b) == block(20, 29, 20, 39)
    assert grid.occupied.sum() == 200


def test_rotated_box_diamond(client: int) -> None:
    # a square of side 0.2 sqrt 2 turned 45 deg around the grid point (1.0, 1.0): |dx|+|dy| < 0.2
    half = 0.1 * math.sqrt(2.0)
    b = box(client, (half, half, 0.2), (1.0, 1.0, 0.2), yaw=math.pi / 4)
    grid = rasterise(client, [b], extent=EXTENT)
    want = set()
    for i in range(-5, 5):
        for j in range(-5, 5):
            # nearest point of cell [i, i+1] x [j, j+1] (in 5 cm units) to the centre
            nx = min(max(0, i), i + 1)
            ny = min(max(0, j), j + 1)
            if abs(nx) + abs(ny) < 4:
                want.add((40 + j, 40 + i))
    assert len(want) == 40
    assert cells(grid, b) == want


def test_cylinder_is_a_disc_of_its_radius(client: int) -> None:
    # radius 0.1 at the centre of cell (row 20, col 20): a 5 x 5 block without its corners
    b = cylinder(client, 0.1, 0.5, (0.025, 0.025, 0.25))
    grid = rasterise(client, [b], extent=EXTENT)
    want = block(18, 22, 18, 22) - {(18, 18), (18, 22), (22, 18), (22, 22)}
    assert cells(grid, b) == want


def test_height_band_slices_and_skips(client: int) -> None:
    above = box(client, (0.2, 0.2, 0.1), (0.0, 1.5, 1.1))  # z 1.0..1.2
    ball = sphere(client, 0.2, (1.0, 2.0, 1.0))  # cut by the band top z = 0.9
    grid = rasterise(client, [above, ball], extent=EXTENT, band=(0.02, 0.9))
    assert cells(grid, above) == set()
    # widest circle in the band: radius sqrt(0.2^2 - 0.1^2) = 0.173 around a grid point
    want = set()
    for i in range(-4, 4):
        for j in range(-4, 4):
            nx = min(max(0, i), i + 1)
            ny = min(max(0, j), j + 1)
            if math.hypot(nx, ny) * 0.05 < math.sqrt(0.03):
                want.add((60 + j, 40 + i))
    assert len(want) == 52
    assert cells(grid, ball) == want
    outline = body_outlines(client, ball, (0.02, 0.9))[0]
    assert isinstance(outline, Disc) and outline.radius == pytest.approx(math.sqrt(0.03))


def test_box_partly_in_band_and_tilted_box(client: int) -> None:
    col = pb.createCollisionShape(
        pb.GEOM_BOX, halfExtents=(0.3, 0.05, 0.05), physicsClientId=client
    )
    # tilted 45 deg about y: only the lower-left part reaches below z = 0.5
    tilted = pb.createMultiBody(
        0,
        col,
        -1,
        (0.0, 0.0, 0.5),
        pb.getQuaternionFromEuler((0, math.pi / 4, 0)),
        physicsClientId=client,
    )
    outline = body_outlines(client, tilted, (0.0, 0.5))[0]
    assert isinstance(outline, Polygon)
    xmin, _, xmax, _ = outline.extent()
    # world x = (lx + lz) / sqrt 2 and z <= 0.5 where lz <= lx (local coordinates of the bar)
    assert xmin == pytest.approx(-0.1 / math.sqrt(2.0), abs=1e-9)
    assert xmax == pytest.approx(0.35 / math.sqrt(2.0), abs=1e-9)


def test_world_cell_conversions() -> None:
    grid = OccupancyGrid.empty((-1.0, -2.0, 1.0, 2.0), 0.05)
    assert grid.shape == (80, 40)
    assert grid.world_to_cell(-1.0, -2.0) == (0, 0)
    assert grid.world_to_cell(0.0, 0.0) == (40, 20)
    assert grid.world_to_cell(-0.001, -0.001) == (39, 19)
    assert grid.cell_to_world(40, 20) == pytest.approx((0.025, 0.025))
    assert not grid.inside(grid.world_to_cell(1.0, 0.0))
    pts = grid.cells_to_world(np.array([[0, 0], [79, 39]]))
    assert np.allclose(pts, [[-0.975, -1.975], [0.975, 1.975]])


def test_png_is_written(tmp_path: Path, client: int) -> None:
    b = box(client, (0.5, 0.25, 0.3), (0.5, 0.25, 0.3))
    grid = rasterise(client, [b], extent=EXTENT)
    grid.save_png(tmp_path / "occ.png", path_cells=np.array([[0, 0], [1, 1]]))
    data = (tmp_path / "occ.png").read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    width, height = int.from_bytes(data[16:20], "big"), int.from_bytes(data[20:24], "big")
    assert (width, height) == (80, 80)
    # decode the pixels: the box is black, row 0 of the image is the grid's top (north) row
    idat = data[data.index(b"IDAT") + 4 : data.index(b"IEND") - 8]
    raw = np.frombuffer(zlib.decompress(idat), np.uint8).reshape(80, 1 + 80 * 3)[:, 1:]
    img = raw.reshape(80, 80, 3)[::-1]
    assert (img[grid.occupied] == 0).all()
    assert img[0, 0].tolist() == img[1, 1].tolist() == [220, 30, 30]  # the path
    free = ~grid.occupied
    free[0, 0] = free[1, 1] = False
    assert (img[free] == 255).all()
    save_cost_png(tmp_path / "cost.png", CostMap(grid).cost_for(0.3))
    assert (tmp_path / "cost.png").stat().st_size > 100


def test_inflation_blocks_within_the_footprint_and_grades_beyond() -> None:
    grid = OccupancyGrid.empty((0.0, 0.0, 3.0, 3.0), 0.05)
    grid.occupied[30, 30] = True
    clear = clearance(grid)
    # distance between cell centres minus half a cell diagonal
    assert clear[30, 40] == pytest.approx(0.5 - 0.05 / math.sqrt(2.0))
    opts = InflationOptions(margin=0.1, gradient_cost=4.0, gradient_reach=0.5)
    cost = inflate(clear, 0.3, opts)
    blocked = ~np.isfinite(cost)
    assert np.array_equal(blocked, clear < 0.4)
    assert cost[np.isfinite(cost)].min() == 1.0
    row = cost[30, 31:60]
    finite = row[np.isfinite(row)]
    assert (np.diff(finite) <= 0).all() and finite[0] > 4.0 and finite[-1] == 1.0
    assert cost.dtype == np.float32
