"""Profiles bounded by polylines and circular arcs (Revit's stairs and rolled steel sections)
read without the geometry kernel: the points enclose every arc, on the side it really runs."""

from __future__ import annotations

import math

import numpy as np
import pytest

ifcopenshell = pytest.importorskip("ifcopenshell")

from bt_manip.bim.shapes import ARC_STEP, _composite_points  # noqa: E402


def _axis(placement: object) -> np.ndarray:
    m = np.eye(4)
    m[:2, 3] = placement.Location.Coordinates[:2]  # type: ignore[attr-defined]
    return m


def _quarter(sense: bool, degrees: bool) -> object:
    """A closed outline: the quarter circle of radius 2 about (1, 1) from 0 to 90 degrees
    (counter-clockwise when ``sense``, else the three quarters the other way), closed by two
    straight lines through the centre."""
    f = ifcopenshell.file(schema="IFC4")
    centre = f.createIfcAxis2Placement2D(f.createIfcCartesianPoint((1.0, 1.0)))
    circle = f.createIfcCircle(centre, 2.0)
    unit = 1.0 if degrees else math.pi / 180
    arc = f.createIfcTrimmedCurve(circle, [f.createIfcParameterValue(0.0)],
                                  [f.createIfcParameterValue(90.0 * unit)], sense, "PARAMETER")
    lines = f.createIfcPolyline([f.createIfcCartesianPoint(p)
                                 for p in ((1.0, 3.0), (1.0, 1.0), (3.0, 1.0))])
    return f.createIfcCompositeCurve([
        f.createIfcCompositeCurveSegment("CONTINUOUS", True, arc),
        f.createIfcCompositeCurveSegment("CONTINUOUS", True, lines)], False)


@pytest.mark.parametrize("degrees", [True, False])
def test_an_arc_is_enclosed_on_the_side_it_runs(degrees: bool) -> None:
    scale = math.pi / 180 if degrees else 1.0
    pts = _composite_points(_quarter(True, degrees), scale, _axis)
    assert pts is not None
    r = np.hypot(pts[:, 0] - 1.0, pts[:, 1] - 1.0)
    on_arc = r > 2.0 + 1e-9  # the arc's points (the lines' ends lie on the circle itself)
    # the arc's points lie in the first quadrant about the centre, just outside the circle
    assert np.all(pts[on_arc, 0] >= 1.0 - 1e-9) and np.all(pts[on_arc, 1] >= 1.0 - 1e-9)
    assert np.all(r[on_arc] <= 2.0 / math.cos(ARC_STEP / 2) + 1e-9)
    assert on_arc.sum() >= math.ceil((math.pi / 2) / ARC_STEP) + 1
    # every point of the true arc lies in the fan of triangles (centre, a vertex, the next)
    arc = pts[on_arc] - 1.0
    angles = np.arctan2(arc[:, 1], arc[:, 0])
    order = np.argsort(angles)
    arc, angles = arc[order], angles[order]
    for a in np.linspace(0.0, math.pi / 2, 200):
        p = 2.0 * np.array([math.cos(a), math.sin(a)])
        k = min(int(np.searchsorted(angles, a, side="right")) - 1, len(arc) - 2)
        v0, v1 = arc[max(k, 0)], arc[max(k, 0) + 1]
        # p is on the centre's side of the chord v0 -> v1 (the fan turns counter-clockwise)
        assert (v1[0] - v0[0]) * (p[1] - v0[1]) - (v1[1] - v0[1]) * (p[0] - v0[0]) >= -1e-12


def test_an_arc_against_the_sense_runs_the_other_way_round() -> None:
    pts = _composite_points(_quarter(False, True), math.pi / 180, _axis)
    assert pts is not None
    r = np.hypot(pts[:, 0] - 1.0, pts[:, 1] - 1.0)
    arc = pts[r > 2.0 + 1e-9]
    # clockwise from 0 to 90 degrees: through 270 and 180, three quarters of the circle
    assert (arc[:, 1] < 0.0).any() and (arc[:, 0] < 0.0).any()
    assert len(arc) >= math.ceil((3 * math.pi / 2) / ARC_STEP) + 1


def test_an_outline_with_another_kind_of_segment_is_left_to_the_kernel() -> None:
    f = ifcopenshell.file(schema="IFC4")
    line = f.createIfcLine(f.createIfcCartesianPoint((0.0, 0.0)),
                           f.createIfcVector(f.createIfcDirection((1.0, 0.0)), 1.0))
    trimmed = f.createIfcTrimmedCurve(line, [f.createIfcParameterValue(0.0)],
                                      [f.createIfcParameterValue(1.0)], True, "PARAMETER")
    curve = f.createIfcCompositeCurve([f.createIfcCompositeCurveSegment("CONTINUOUS", True,
                                                                         trimmed)], False)
    assert _composite_points(curve, 1.0, _axis) is None
