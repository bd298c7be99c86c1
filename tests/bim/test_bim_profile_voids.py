"""An extruded profile with voids (a table top with a hole, a hollow column) is read for an
obstacle's footprint by its outer curve, without the geometry kernel: the same hull and
heights as the kernel's mesh; where the area counts (a wall's body) it is still not read."""

from __future__ import annotations

import math

import numpy as np
import pytest

ifcopenshell = pytest.importorskip("ifcopenshell")
pytest.importorskip("ifcopenshell.geom")

from bt_manip.bim.hulls import hull_xy  # noqa: E402
from bt_manip.bim.shapes import ShapeReader, _profile_points  # noqa: E402


def _polyline(f: object, pts: list[tuple[float, float]]) -> object:
    return f.createIfcPolyline(  # type: ignore[attr-defined]
        [f.createIfcCartesianPoint(p) for p in [*pts, pts[0]]])  # type: ignore[attr-defined]


def _holed_desk(yaw: float) -> tuple[object, object, object]:
    """A file holding a desk: an L-shaped top with a square hole, extruded 0.75 m up, placed
    at (2, 1) turned by ``yaw``; returns the file, the desk and its profile."""
    f = ifcopenshell.file(schema="IFC4")
    outer = _polyline(f, [(0.0, 0.0), (1.6, 0.0), (1.6, 0.6), (0.6, 0.6), (0.6, 1.4),
                          (0.0, 1.4)])
    hole = _polyline(f, [(0.2, 0.2), (0.4, 0.2), (0.4, 0.4), (0.2, 0.4)])
    profile = f.createIfcArbitraryProfileDefWithVoids("AREA", None, outer, [hole])
    origin = f.createIfcAxis2Placement3D(f.createIfcCartesianPoint((0.0, 0.0, 0.0)))
    solid = f.createIfcExtrudedAreaSolid(profile, origin,
                                         f.createIfcDirection((0.0, 0.0, 1.0)), 0.75)
    context = f.createIfcGeometricRepresentationContext(None, "Model", 3, 1e-5, origin)
    body = f.createIfcShapeRepresentation(context, "Body", "SweptSolid", [solid])
    place = f.createIfcLocalPlacement(None, f.createIfcAxis2Placement3D(
        f.createIfcCartesianPoint((2.0, 1.0, 0.0)), f.createIfcDirection((0.0, 0.0, 1.0)),
        f.createIfcDirection((math.cos(yaw), math.sin(yaw), 0.0))))
    desk = f.createIfcFurniture(ifcopenshell.guid.new(), None, "Desk", None, None, place,
                                f.createIfcProductDefinitionShape(None, None, [body]))
    return f, desk, profile


@pytest.mark.parametrize("yaw", [0.0, 0.7, -2.1])
def test_a_profile_with_voids_gives_the_kernels_hull_without_the_kernel(
        yaw: float, monkeypatch: pytest.MonkeyPatch) -> None:
    f, desk, _ = _holed_desk(yaw)
    kernel = ShapeReader(1.0, f).mesh(desk)[0]
    reader = ShapeReader(1.0, f)
    monkeypatch.setattr(ShapeReader, "mesh", lambda self, element: pytest.fail(
        "the kernel was asked for a profile with voids"))
    direct = reader.points(desk)
    # the same corners of the footprint's hull (the hole's corners lie inside it) ...
    ours, theirs = hull_xy(direct[:, :2]), hull_xy(kernel[:, :2])
    assert len(ours) == len(theirs) == 5  # the L's reflex corner is not on the hull
    for corner in theirs:
        assert np.min(np.hypot(*(ours - corner).T)) < 1e-9
    # ... and the same heights
    assert direct[:, 2].min() == pytest.approx(kernel[:, 2].min(), abs=1e-9)
    assert direct[:, 2].max() == pytest.approx(kernel[:, 2].max(), abs=1e-9)


def test_where_the_area_counts_a_profile_with_voids_is_not_read() -> None:
    _, _, profile = _holed_desk(0.0)
    assert _profile_points(profile) is None  # a wall's body: left to the kernel
    outline = _profile_points(profile, angle_unit=1.0)
    assert outline is not None and len(outline) == 6  # the outer curve, closed once
