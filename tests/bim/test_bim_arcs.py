"""Profiles bounded by polylines and circular arcs (Revit's stairs and rolled steel sections,
Bonsai's indexed poly curves) read without the geometry kernel: the points enclose every arc,
on the side it really runs."""

from __future__ import annotations

import math

import numpy as np
import pytest

ifcopenshell = pytest.importorskip("ifcopenshell")

from bt_manip.bim.shapes import (  # noqa: E402
    ARC_STEP,
    _composite_points,
    _indexed_points,
    _profile_points,
)


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


FILES: list[object] = []
"""The files the tests' curves live in, kept while the tests run (an entity does not keep its
file alive)."""


def _indexed(points: list[tuple[float, float]], segments: list[tuple[str, tuple[int, ...]]],
             f: object = None) -> object:
    """An IfcIndexedPolyCurve through ``points`` made of ``segments`` (kind, 1-based indices),
    in ``f`` (a new IFC4 file without)."""
    if f is None:
        f = ifcopenshell.file(schema="IFC4")
        FILES.append(f)
    made = [f.create_entity(kind, indices) for kind, indices in segments]
    return f.createIfcIndexedPolyCurve(
        f.createIfcCartesianPointList2D(points), made, False)


def test_line_segments_give_their_points_in_turn_each_once() -> None:
    square = [(0.0, 0.0), (2.0, 0.0), (2.0, 1.0), (0.0, 1.0)]
    curve = _indexed(square, [("IfcLineIndex", (1, 2, 3)), ("IfcLineIndex", (3, 4, 1))])
    for arcs in (True, False):
        pts = _indexed_points(curve, arcs)
        assert pts is not None
        assert pts.tolist() == [[0.0, 0.0], [2.0, 0.0], [2.0, 1.0], [0.0, 1.0], [0.0, 0.0]]


def _half_disc() -> tuple[object, object]:
    """A closed profile (and its file): the half disc of radius 1 about (0, 0) above the x
    axis, from (1, 0) through (0, 1) to (-1, 0), closed by the diameter."""
    f = ifcopenshell.file(schema="IFC4")
    FILES.append(f)
    points = [(1.0, 0.0), (0.0, 1.0), (-1.0, 0.0)]
    curve = _indexed(points, [("IfcArcIndex", (1, 2, 3)), ("IfcLineIndex", (3, 1))], f)
    return f.createIfcArbitraryClosedProfileDef("AREA", None, curve), f


def test_an_arc_segment_is_enclosed_on_the_side_it_runs() -> None:
    profile, _ = _half_disc()
    pts = _profile_points(profile, _axis, 1.0)
    assert pts is not None
    r = np.hypot(pts[:, 0], pts[:, 1])
    assert np.all(pts[:, 1] >= -1e-9)  # above the diameter: the arc runs through (0, 1)
    assert np.all(r >= 1.0 - 1e-9) and np.all(r <= 1.0 / math.cos(ARC_STEP / 2) + 1e-9)
    assert len(pts) >= math.ceil(math.pi / ARC_STEP) + 1
    # every point of the true arc lies inside the polygon (convex, counter-clockwise)
    nxt = np.roll(pts, -1, axis=0)
    for a in np.linspace(0.0, math.pi, 181):
        p = np.array([math.cos(a), math.sin(a)])
        turn = (nxt[:, 0] - pts[:, 0]) * (p[1] - pts[:, 1]) - (nxt[:, 1] - pts[:, 1]) * (
            p[0] - pts[:, 0])
        assert np.all(turn >= -1e-12)


def test_an_arc_segment_runs_clockwise_when_its_middle_point_says_so() -> None:
    # from (1, 0) through (0, -1) to (-1, 0): the lower half, clockwise
    points = [(1.0, 0.0), (0.0, -1.0), (-1.0, 0.0)]
    curve = _indexed(points, [("IfcArcIndex", (1, 2, 3)), ("IfcLineIndex", (3, 1))])
    pts = _indexed_points(curve, True)
    assert pts is not None and np.all(pts[:, 1] <= 1e-9) and (pts[:, 1] < -0.99).any()


def test_the_kernel_mesh_of_an_arc_profile_lies_within_its_points() -> None:
    import ifcopenshell.geom

    profile, f = _half_disc()
    solid = f.createIfcExtrudedAreaSolid(profile, f.createIfcAxis2Placement3D(
        f.createIfcCartesianPoint((0.0, 0.0, 0.0))), f.createIfcDirection((0.0, 0.0, 1.0)), 0.5)
    shape = ifcopenshell.geom.create_shape(ifcopenshell.geom.settings(), solid)
    verts = np.asarray(getattr(shape, "verts", None) or shape.geometry.verts).reshape(-1, 3)
    pts = _profile_points(profile, _axis, 1.0)
    assert pts is not None
    nxt = np.roll(pts, -1, axis=0)
    for p in verts[:, :2]:
        turn = (nxt[:, 0] - pts[:, 0]) * (p[1] - pts[:, 1]) - (nxt[:, 1] - pts[:, 1]) * (
            p[0] - pts[:, 0])
        assert np.all(turn >= -1e-9)


def test_arcs_off_the_point_list_or_for_a_body_are_left_to_the_kernel() -> None:
    profile, _ = _half_disc()
    assert _profile_points(profile, _axis) is None  # a body's outline: its area counts
    points = [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0)]
    assert _indexed_points(_indexed(points, [("IfcLineIndex", (1, 2, 4))]), True) is None
    # three points on one line bound no arc
    flat = [(0.0, 0.0), (1.0, 0.0), (2.0, 0.0), (1.0, 1.0)]
    curve = _indexed(flat, [("IfcArcIndex", (1, 2, 3)), ("IfcLineIndex", (3, 4, 1))])
    assert _indexed_points(curve, True) is None
