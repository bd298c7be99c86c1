"""The memory-lean grid builder against a straightforward reference, bit for bit.

The reference is how the grid used to be built: every cell of a shape's bounding box tested at
once, scipy's Euclidean distance transform in float64, and :func:`inflate` on the full float64
clearance grid. The builder under test draws shapes in blocks of rows, computes exact integer
squared distances, and reads cost grids from a table; the occupied cells, clearances, cost
grids and planned paths must be the same, bit for bit.
"""

from __future__ import annotations

import math
from collections.abc import Iterator

import numpy as np
import pybullet as pb
import pytest
from scipy.ndimage import distance_transform_edt

from bt_manip.navigation import grid as grid_module
from bt_manip.navigation.astar import plan_verbose
from bt_manip.navigation.costmap import CostMap, InflationOptions, clearance, inflate
from bt_manip.navigation.distance import squared_distances, squared_distances_dtype
from bt_manip.navigation.footprint import PlanarFootprint
from bt_manip.navigation.grid import OccupancyGrid, _disc_hits, _polygon_hits, rasterise
from bt_manip.navigation.planner import plan_path
from bt_manip.navigation.shapes import Disc, body_outlines


@pytest.fixture()
def client() -> Iterator[int]:
    c = pb.connect(pb.DIRECT)
    yield c
    pb.disconnect(c)


def reference_occupancy(client: int, bodies: list[int], like: OccupancyGrid) -> np.ndarray:
    """Every cell of each shape's bounding box tested in one go (no blocks)."""
    occ = np.zeros(like.shape, bool)
    rows, cols = like.shape
    res = like.resolution
    x0, y0 = like.origin
    for body in bodies:
        for o in body_outlines(client, body, like.band):
            xmin, ymin, xmax, ymax = o.extent()
            c0 = max(0, math.floor((xmin - x0) / res))
            c1 = min(cols - 1, math.floor((xmax - x0) / res))
            r0 = max(0, math.floor((ymin - y0) / res))
            r1 = min(rows - 1, math.floor((ymax - y0) / res))
            if c0 > c1 or r0 > r1:
                continue
            cc, rr = np.meshgrid(np.arange(c0, c1 + 1), np.arange(r0, r1 + 1))
            lx = x0 + cc * res
            ly = y0 + rr * res
            hits = _disc_hits if isinstance(o, Disc) else _polygon_hits
            hit = hits(o, lx, ly, res)  # type: ignore[arg-type]
            occ[rr[hit], cc[hit]] = True
    return occ


def reference_clearance(occ: np.ndarray, res: float) -> np.ndarray:
    if not occ.any():
        return np.full(occ.shape, np.inf)
    return distance_transform_edt(~occ) * res - res / math.sqrt(2.0)


def same_bits(a: np.ndarray, b: np.ndarray) -> bool:
    return a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes()


def random_world(client: int, rng: np.random.Generator) -> list[int]:
    """A few boxes (turned any way), cylinders and spheres on a 6 m x 4 m floor."""
    bodies = []
    for _ in range(int(rng.integers(3, 9))):
        kind = rng.integers(3)
        pos = (float(rng.uniform(0.0, 6.0)), float(rng.uniform(0.0, 4.0)), 0.4)
        if kind == 0:
            half = rng.uniform(0.02, 1.2, 3)
            col = pb.createCollisionShape(
                pb.GEOM_BOX, halfExtents=half.tolist(), physicsClientId=client
            )
            quat = pb.getQuaternionFromEuler((0.0, 0.0, float(rng.uniform(-math.pi, math.pi))))
        elif kind == 1:
            col = pb.createCollisionShape(
                pb.GEOM_CYLINDER,
                radius=float(rng.uniform(0.03, 0.6)),
                height=0.6,
                physicsClientId=client,
            )
            quat = (0.0, 0.0, 0.0, 1.0)
        else:
            col = pb.createCollisionShape(
                pb.GEOM_SPHERE, radius=float(rng.uniform(0.03, 0.5)), physicsClientId=client
            )
            quat = (0.0, 0.0, 0.0, 1.0)
        bodies.append(pb.createMultiBody(0, col, -1, pos, quat, physicsClientId=client))
    return bodies


def test_squared_distances_match_scipy_on_random_grids() -> None:
    rng = np.random.default_rng(7)
    shapes = [(1, 1), (1, 37), (41, 1), (2, 2)] + [tuple(rng.integers(1, 90, 2)) for _ in range(80)]
    for shape in shapes:
        density = float(rng.choice([0.0005, 0.01, 0.1, 0.5, 0.95, 1.0]))
        occ = rng.random(shape) < density
        occ.reshape(-1)[rng.integers(occ.size)] = True
        d2 = squared_distances(occ)
        assert d2 is not None and d2.dtype == np.uint32
        assert same_bits(np.sqrt(d2.astype(np.float64)), distance_transform_edt(~occ)), shape
    assert squared_distances(np.zeros((5, 7), bool)) is None


def test_squared_distances_past_32_bits_are_exact() -> None:
    assert squared_distances_dtype((4000, 6000)) == np.uint32
    assert squared_distances_dtype((1, 70_000)) == np.int64
    occ = np.zeros((2, 70_000), bool)
    occ[0, 0] = True
    d2 = squared_distances(occ)
    assert d2 is not None and d2.dtype == np.int64
    assert int(d2[1, -1]) == 69_999**2 + 1
    assert same_bits(np.sqrt(d2.astype(np.float64)), distance_transform_edt(~occ))


@pytest.mark.parametrize(
    "options",
    [
        InflationOptions(),
        InflationOptions(margin=0.0, gradient_cost=2.5, gradient_reach=1.7),
        InflationOptions(margin=0.2, gradient_cost=0.0),
    ],
)
def test_cost_grids_match_inflating_the_float_clearance(options: InflationOptions) -> None:
    rng = np.random.default_rng(11)
    for _ in range(12):
        res = float(rng.choice([0.02, 0.05, 0.1]))
        rows, cols = (int(v) for v in rng.integers(20, 120, 2))
        grid = OccupancyGrid.empty((0.0, 0.0, cols * res, rows * res), res)
        grid.occupied[:] = rng.random(grid.shape) < float(rng.choice([0.0, 0.001, 0.02, 0.2]))
        ref_clear = reference_clearance(grid.occupied, res)
        assert same_bits(clearance(grid), ref_clear)
        cm = CostMap(grid, options)
        assert same_bits(cm.clear, ref_clear)
        for w in (0.0, 0.1234567, 0.3, 0.55, 2.0):
            assert same_bits(cm.cost_for(w), inflate(ref_clear, round(w, 4), options)), (res, w)
        r, c = int(rng.integers(rows)), int(rng.integers(cols))
        assert cm.clearance_of_cell((r, c)) == ref_clear[r, c]


def test_random_worlds_give_the_reference_grid_costs_and_paths(
    client: int, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(grid_module, "BLOCK_CELLS", 37)  # many blocks per shape
    rng = np.random.default_rng(3)
    footprint = PlanarFootprint.rectangle(0.5, 0.4)
    found = 0
    for _ in range(5):
        for body in range(pb.getNumBodies(physicsClientId=client)):
            pb.removeBody(pb.getBodyUniqueId(body, physicsClientId=client), physicsClientId=client)
        bodies = random_world(client, rng)
        extent = (-0.5, -0.5, 6.5, 4.5)
        grid = rasterise(client, bodies, extent=extent, remember=False)
        remembered = rasterise(client, bodies, extent=extent)
        ref_occ = reference_occupancy(client, bodies, grid)
        assert ref_occ.any()
        assert same_bits(grid.occupied, ref_occ)
        assert same_bits(remembered.occupied, ref_occ)
        ref_cost = inflate(reference_clearance(ref_occ, grid.resolution), 0.2)
        cm = CostMap(grid)
        assert same_bits(cm.cost_for(footprint), ref_cost)
        free = np.argwhere(np.isfinite(ref_cost))
        for _ in range(4):
            a, b = free[rng.integers(len(free), size=2)]
            ref = plan_verbose(ref_cost, (int(a[0]), int(a[1])), (int(b[0]), int(b[1])))
            plan = plan_path(cm, footprint, grid.cell_to_world(*a), grid.cell_to_world(*b))
            assert plan.ok == ref.found
            if ref.found:
                found += 1
                assert plan.cells is not None and np.array_equal(plan.cells, ref.path)
    assert found > 5
