"""Files the way small exports, surveyed models and IFC4.3 sample models write them: no
storey (elements in the building), columns placed on a design grid (IfcGridPlacement), no
spaces and no slab, building services standing in a room, a header naming the schema IFC4X3,
a storey thousands of kilometres from the model's origin."""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml

pytest.importorskip("ifcopenshell")

import ifcopenshell
import ifcopenshell.api
from ifc_buildings import PANELS, _matrix, add_wall, bim_cli, empty_storey, three_rooms

from bt_manip.bim.convert import BimOptions, convert
from bt_manip.sim.world_reader import parse_world

api = ifcopenshell.api.run
HUSKY_RADIUS = 0.6  # half of the 1.20 m the robot needs across (husky_ur3 with its arm tucked)


def _world(path: Path) -> dict[str, Any]:
    return yaml.safe_load(path.read_text())


def test_a_file_without_storeys_is_read_whole_as_one_level(tmp_path, capsys):
    flat = three_rooms(with_storey=False).write(tmp_path / "flat.ifc")
    storeyed = three_rooms().write(tmp_path / "storeyed.ifc")
    code, out, err = bim_cli(capsys, str(flat), "--out", str(tmp_path / "flat"))
    assert code == 0, err
    assert ("level 'Building' (IfcBuilding, elevation 0.00 m: no IfcBuildingStorey in the "
            "file: every element read, as one level)") in out
    assert f"{len(PANELS)} elements to install" in out
    c = convert(BimOptions(storeyed, tmp_path / "storeyed"))
    a, b = _world(tmp_path / "flat" / "world.yaml"), _world(c.world_path)
    # the same building: walls, openings, furniture, objects to install, poses
    for key in ("walls", "furniture", "objects", "poses"):
        assert a[key] == b[key], key
    assert len(a["walls"]) == 6


def test_storey_given_for_a_file_without_storeys(tmp_path, capsys):
    flat = three_rooms(with_storey=False).write(tmp_path / "flat.ifc")
    code, _, err = bim_cli(capsys, str(flat), "--out", str(tmp_path / "o"), "--storey", "0")
    assert code == 2
    assert err.strip() == (
        "--storey: the file has no IfcBuildingStorey: it is read whole, as one level "
        "(IfcBuilding 'Building'); leave --storey out")
    assert not (tmp_path / "o").exists()


def _extruded_box(f: Any, body: Any, x: float, y: float, height: float) -> Any:
    """A product shape: an x by y (mm) rectangle centred on the placement, extruded up."""
    origin = f.createIfcAxis2Placement2D(f.createIfcCartesianPoint((0.0, 0.0)))
    profile = f.createIfcRectangleProfileDef("AREA", None, origin, x, y)
    solid = f.createIfcExtrudedAreaSolid(
        profile, f.createIfcAxis2Placement3D(f.createIfcCartesianPoint((0.0, 0.0, 0.0))),
        f.createIfcDirection((0.0, 0.0, 1.0)), height)
    rep = f.createIfcShapeRepresentation(body, "Body", "SweptSolid", [solid])
    return f.createIfcProductDefinitionShape(None, None, [rep])


GRID_AT = (2.0, 1.0, math.radians(30))
"""The grid's placement in the storey: (x, y) in metres and its heading."""


def _gridempty_storey() -> tuple[Any, dict[str, Any]]:
    """A hall whose grid is turned 30 deg and moved to (2, 1) m: axes 1 (y = 0, drawn towards
    +x) and 2 (y = 4 m, drawn towards -x but SameSense false: it runs towards +x) across axes
    A (x = 0) and B (x = 6 m), both drawn towards +y, and an arc axis R; 30 x 20 cm columns
    2.5 m high on the crossings."""
    f, body, storey = empty_storey()
    grid = api("root.create_entity", f, ifc_class="IfcGrid", name="Grid")
    api("geometry.edit_object_placement", f, product=grid, matrix=_matrix(*GRID_AT[:2], 0.0,
                                                                          GRID_AT[2]))
    api("spatial.assign_container", f, products=[grid], relating_structure=storey)

    def pt(x: float, y: float) -> Any:
        return f.createIfcCartesianPoint((float(x), float(y)))

    def axis(tag: str, a: tuple[float, float], b: tuple[float, float], same: bool = True) -> Any:
        return f.createIfcGridAxis(tag, f.createIfcPolyline([pt(*a), pt(*b)]), same)

    one = axis("1", (-1000, 0), (9000, 0))
    two = axis("2", (9000, 4000), (-1000, 4000), same=False)
    a = axis("A", (0, -1000), (0, 5000))
    b = axis("B", (6000, -1000), (6000, 5000))
    arc = f.createIfcGridAxis("R", f.createIfcCircle(
        f.createIfcAxis2Placement2D(pt(0, 0)), 3000.0), True)
    grid.UAxes, grid.VAxes, grid.WAxes = [one, two], [a, b], [arc]
    columns: dict[str, Any] = {}

    def column(name: str, axes: list[Any], offsets: tuple[float, ...] = (0.0, 0.0),
               ref: Any = None) -> None:
        el = api("root.create_entity", f, ifc_class="IfcColumn", name=name)
        el.Representation = _extruded_box(f, body, 300.0, 200.0, 2500.0)
        el.ObjectPlacement = f.createIfcGridPlacement(
            f.createIfcVirtualGridIntersection(axes, offsets), ref)
        api("spatial.assign_container", f, products=[el], relating_structure=storey)
        columns[name] = el

    column("A1", [a, one])
    column("B2 offset", [b, two], offsets=(500.0, 300.0))
    column("A2 turned", [a, two], ref=f.createIfcDirection((0.0, 1.0)))
    column("B1 facing A1", [b, one],
           ref=f.createIfcVirtualGridIntersection([a, one], (0.0, 0.0)))
    column("On the arc", [arc, one])
    return f, columns


def _on_grid(x: float, y: float) -> tuple[float, float]:
    """A point of the grid's plane (m) in the storey."""
    gx, gy, turn = GRID_AT
    c, s = math.cos(turn), math.sin(turn)
    return gx + c * x - s * y, gy + s * x + c * y


def _same_heading(a: float, b: float) -> bool:
    """Headings equal up to a half turn (a box's yaw says its axis, not its sense)."""
    return abs(math.remainder(a - b, math.pi)) < 1e-3


def test_columns_placed_on_a_design_grid_stand_where_its_axes_cross(tmp_path):
    f, columns = _gridempty_storey()
    path = tmp_path / "grid.ifc"
    f.write(str(path))
    c = convert(BimOptions(path, tmp_path / "out"))
    boxes = {item["name"]: item for item in _world(c.world_path)["furniture"]}
    turn = GRID_AT[2]
    # each column: where its axes cross (after their offsets), and its x axis
    expected = {
        "a1": (_on_grid(0.0, 0.0), turn + math.pi / 2),  # along axis A, which runs to +y
        # axis B moved 0.5 m to its left (-x), axis 2 (running to +x) 0.3 m to its left (+y)
        "b2_offset": (_on_grid(5.5, 4.3), turn + math.pi / 2),
        "a2_turned": (_on_grid(0.0, 4.0), turn + math.pi / 2),  # the direction (0, 1) given
        "b1_facing_a1": (_on_grid(6.0, 0.0), turn + math.pi),  # towards the crossing A1
    }
    for name, ((x, y), heading) in expected.items():
        box = boxes[name]
        assert box["pose"]["xyz"][:2] == pytest.approx([x, y], abs=2e-4), name
        assert box["size"][:2] == pytest.approx([0.3, 0.2], abs=1e-3), name
        assert _same_heading(box["pose"]["rpy"][2], heading), name
    assert "on_the_arc" not in boxes
    assert c.building.counts["other obstacles"] == 5
    skipped = dict(c.building.skipped)
    assert skipped[f"#{columns['On the arc'].id()} IfcColumn 'On the arc'"] == (
        "its grid placement: grid axis 'R' is an IfcCircle: only straight grid axes "
        "(polylines and lines) are read")


def test_a_lone_wall_without_spaces_or_slab_becomes_a_world(tmp_path):
    f, body, storey = empty_storey()
    add_wall(f, body, storey, "Lone", 3.0, 0.3, np.eye(4))
    path = tmp_path / "wall.ifc"
    f.write(str(path))
    c = convert(BimOptions(path, tmp_path / "out"))
    spec = parse_world(c.world_path)
    assert len(spec.walls) == 1
    # the start is beside the wall (0..3 m x 0..0.3 m), the whole robot clear of it
    x, y = c.start[:2]
    gap_x = max(0.0 - x, x - 3.0, 0.0)
    gap_y = max(0.0 - y, y - 0.3, 0.0)
    assert math.hypot(gap_x, gap_y) >= HUSKY_RADIUS


def test_a_closed_cell_without_spaces_leaves_the_start_outside(tmp_path, capsys):
    # a closed 1 m square room (no spaces): the extent holds no spot for the robot, and the
    # floor around it is outside the walls, where it may start
    f, body, storey = empty_storey()
    for name, m in (("S", _matrix(0.0, 0.0, 0.0, 0.0)), ("N", _matrix(0.0, 1.0, 0.0, 0.0)),
                    ("W", _matrix(0.0, 0.0, 0.0, math.pi / 2)),
                    ("E", _matrix(1.0, 0.0, 0.0, math.pi / 2))):
        add_wall(f, body, storey, name, 1.0, 0.1, m)
    path = tmp_path / "cell.ifc"
    f.write(str(path))
    code, out, err = bim_cli(capsys, str(path), "--out", str(tmp_path / "o"))
    assert code == 0, err
    x, y = (float(v) for v in out.split("robot start at (")[1].split(")")[0].split(", "))
    assert not (-0.2 < x < 1.2 and -0.2 < y < 1.2)  # outside, clear of the walls
    assert parse_world(tmp_path / "o" / "world.yaml").walls


def test_building_services_standing_in_a_room_are_obstacles(tmp_path):
    f, body, storey = empty_storey()
    bath = api("root.create_entity", f, ifc_class="IfcSanitaryTerminal", name="Bath")
    bath.Representation = _extruded_box(f, body, 1700.0, 700.0, 550.0)
    api("geometry.edit_object_placement", f, product=bath, matrix=_matrix(2.0, 3.0, 0.0, 0.0))
    heater = api("root.create_entity", f, ifc_class="IfcSpaceHeater", name="Radiator")
    heater.Representation = _extruded_box(f, body, 1000.0, 100.0, 600.0)
    api("geometry.edit_object_placement", f, product=heater,
        matrix=_matrix(5.0, 1.0, 0.15, 0.0))
    pipe = api("root.create_entity", f, ifc_class="IfcPipeSegment", name="Pipe")
    pipe.Representation = _extruded_box(f, body, 50.0, 50.0, 2000.0)
    api("geometry.edit_object_placement", f, product=pipe, matrix=_matrix(4.0, 4.0, 0.0, 0.0))
    api("spatial.assign_container", f, products=[bath, heater, pipe], relating_structure=storey)
    path = tmp_path / "bath.ifc"
    f.write(str(path))
    c = convert(BimOptions(path, tmp_path / "out"))
    boxes = {item["name"]: item for item in _world(c.world_path)["furniture"]}
    assert set(boxes) == {"bath", "radiator"}  # pipes are not read
    assert boxes["bath"]["pose"]["xyz"][:2] == pytest.approx([2.0, 3.0], abs=1e-3)
    assert boxes["bath"]["size"][:2] == pytest.approx([1.7, 0.7], abs=1e-3)
    assert boxes["radiator"]["pose"]["xyz"][:2] == pytest.approx([5.0, 1.0], abs=1e-3)
    assert c.building.counts["other obstacles"] == 2
    # neither walls nor slabs: the floor's extent is that of what stands on it
    assert c.building.extent == pytest.approx((1.15, 0.95, 5.5, 3.35), abs=1e-3)



@pytest.mark.parametrize("header", ["IFC4X3", "IFC4X3_ADD2"])
def test_ifc4x3_files_named_by_any_release(tmp_path, header):
    # early IFC4.3 files name the schema IFC4X3, read as its final release IFC4X3_ADD2
    f, body, storey = empty_storey(schema="IFC4X3_ADD2")
    add_wall(f, body, storey, "Lone", 3.0, 0.3, np.eye(4))
    written = tmp_path / "written.ifc"
    f.write(str(written))
    path = tmp_path / "hall.ifc"
    path.write_bytes(written.read_bytes().replace(b"'IFC4X3_ADD2'", f"'{header}'".encode()))
    c = convert(BimOptions(path, tmp_path / "out"))
    assert c.schema == "IFC4X3"
    assert len(parse_world(c.world_path).walls) == 1


def test_an_ifc4_release_the_parser_lacks_is_named_at_its_line(tmp_path, capsys):
    f, _, _ = empty_storey(schema="IFC4X3_ADD2")
    written = tmp_path / "written.ifc"
    f.write(str(written))
    path = tmp_path / "hall.ifc"
    data = written.read_bytes().replace(b"'IFC4X3_ADD2'", b"'IFC4X1'")
    path.write_bytes(data)
    line = data[:data.index(b"'IFC4X1'")].count(b"\n") + 1
    code, _, err = bim_cli(capsys, str(path), "--out", str(tmp_path / "o"))
    assert code == 2
    assert err.strip() == (f"{path}:{line}: schema IFC4X1 is not read; IFC2X3, IFC4 and IFC4X3 "
                           "files are")


def test_a_model_far_from_its_origin_is_moved_to_the_worlds(tmp_path, capsys):
    # the three rooms, placed on a storey 500 km east and 4,000 km north of the model's
    # origin (surveyed coordinates), with a survey marker (a 5 cm slab) at the origin
    near = three_rooms()
    far = three_rooms()
    f = far.file
    api("geometry.edit_object_placement", f, product=far.storey,
        matrix=_matrix(500_000.0, 4_000_000.0, 0.0, 0.0))
    storey_at = far.storey.ObjectPlacement
    for product in f.by_type("IfcProduct"):
        at = product.ObjectPlacement
        if at is not None and at.PlacementRelTo is None and not any(
                product.is_a(c) for c in ("IfcSite", "IfcBuilding", "IfcBuildingStorey")):
            at.PlacementRelTo = storey_at
    marker = api("root.create_entity", f, ifc_class="IfcSlab", name="Survey marker")
    marker.Representation = _extruded_box(f, far.body, 50.0, 50.0, 10.0)
    api("geometry.edit_object_placement", f, product=marker, matrix=np.eye(4))
    api("spatial.assign_container", f, products=[marker], relating_structure=far.storey)
    code, out, err = bim_cli(capsys, str(far.write(tmp_path / "far.ifc")), "--out",
                          str(tmp_path / "far"))
    assert code == 0, err
    assert ("note: the storey lies 4,031.1 km from the model's origin: the world is moved; "
            "the model's x, y = the world's + (500000, 4000000) m") in out
    c = convert(BimOptions(near.write(tmp_path / "near.ifc"), tmp_path / "near"))
    a, b = _world(tmp_path / "far" / "world.yaml"), _world(c.world_path)
    # the same world, walls to poses, as the building at the origin gives: to the millimetre,
    # and spots found on the 5 cm floor grid (the stock, the start, the spaces' poses) to a
    # cell (which cell wins a tie may depend on the last bit of a coordinate)
    assert _alike(a["walls"], b["walls"], 1e-3)
    for key in ("objects", "poses", "robots", "groups"):
        assert _alike(a[key], b[key], 0.051), key
    assert "(500000, 4000000) m" in a["description"]
    far_targets = [e["target"] for e in
                   json.loads((tmp_path / "far" / "schedule.json").read_text())["elements"]]
    near_targets = [e["target"] for e in json.loads(c.schedule_path.read_text())["elements"]]
    assert _alike(far_targets, near_targets, 1e-3)


def _alike(a: Any, b: Any, tol: float) -> bool:
    """Equal, numbers within ``tol``, through dicts and lists."""
    if isinstance(a, dict) and isinstance(b, dict):
        return a.keys() == b.keys() and all(_alike(a[k], b[k], tol) for k in a)
    if isinstance(a, list) and isinstance(b, list):
        return len(a) == len(b) and all(_alike(x, y, tol) for x, y in zip(a, b, strict=True))
    if isinstance(a, int | float) and isinstance(b, int | float):
        return abs(a - b) <= tol
    return bool(a == b)
