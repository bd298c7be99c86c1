"""Files whose references go round in a loop, as a broken or hostile file may: placements
relative to one another, representations that map themselves. Each element concerned is left
out (an obstacle) or refused (an element to install) with the loop named, never a Python
error or a crash of the geometry kernel."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

pytest.importorskip("ifcopenshell")

import ifcopenshell.api
from ifc_buildings import bim_cli, three_rooms

from bt_manip.sim.world_reader import parse_world

api = ifcopenshell.api.run


def test_placements_that_loop_leave_their_elements_out(tmp_path, capsys):
    b = three_rooms(with_tasks=False)
    south, north = b.walls["South"].ObjectPlacement, b.walls["North"].ObjectPlacement
    south.PlacementRelTo, north.PlacementRelTo = north, south  # each relative to the other
    path = b.write(tmp_path / "loop.ifc")
    code, out, err = bim_cli(capsys, str(path), "--out", str(tmp_path / "o"))
    assert code == 0, err
    assert (f"#{b.walls['South'].id()} IfcWall 'South' (its placements loop "
            f"(#{south.id()} -> #{north.id()} -> #{south.id()}))") in out
    walls = parse_world(tmp_path / "o" / "world.yaml").walls
    assert len(walls) == 4  # the other four

    # the storey's own placement in a loop: no floor height, the building is refused
    b = three_rooms(with_tasks=False)
    api("geometry.edit_object_placement", b.file, product=b.storey, matrix=np.eye(4))
    at = b.storey.ObjectPlacement
    at.PlacementRelTo = b.walls["West"].ObjectPlacement
    b.walls["West"].ObjectPlacement.PlacementRelTo = at
    path = b.write(tmp_path / "storey_loop.ifc")
    code, out, err = bim_cli(capsys, str(path), "--out", str(tmp_path / "o2"))
    assert code == 2
    assert f"#{b.storey.id()} IfcBuildingStorey 'Ground floor': its elevation cannot be read: " \
           "its placements loop" in err



def _self_mapping(f: Any, body: Any) -> Any:
    """A body whose mapped representation holds a mapped item of itself."""
    origin = f.createIfcAxis2Placement3D(f.createIfcCartesianPoint((0.0, 0.0, 0.0)))
    inner = f.createIfcShapeRepresentation(body, "Body", "MappedRepresentation", [])
    operator = f.createIfcCartesianTransformationOperator3D(
        None, None, f.createIfcCartesianPoint((0.0, 0.0, 0.0)), 1.0, None)
    item = f.createIfcMappedItem(f.createIfcRepresentationMap(origin, inner), operator)
    inner.Items = [item]
    outer = f.createIfcShapeRepresentation(body, "Body", "MappedRepresentation", [item])
    return f.createIfcProductDefinitionShape(None, None, [outer]), item


def test_a_representation_that_maps_itself(tmp_path, capsys):
    # an obstacle: left out, with the loop named
    b = three_rooms(with_tasks=False)
    proxy = api("root.create_entity", b.file, ifc_class="IfcBuildingElementProxy", name="Loop")
    api("geometry.edit_object_placement", b.file, product=proxy, matrix=np.eye(4))
    api("spatial.assign_container", b.file, products=[proxy], relating_structure=b.storey)
    proxy.Representation, item = _self_mapping(b.file, b.body)
    path = b.write(tmp_path / "proxy.ifc")
    code, out, err = bim_cli(capsys, str(path), "--out", str(tmp_path / "o"))
    assert code == 0, err
    assert (f"#{proxy.id()} IfcBuildingElementProxy 'Loop' (its mapped representations loop "
            f"(#{item.MappingSource.id()} -> #{item.MappingSource.id()}))") in out

    # an element to install (read whole, by the geometry kernel): refused at its line
    b = three_rooms()
    panel = b.panels[0]
    panel.Representation, item = _self_mapping(b.file, b.body)
    path = b.write(tmp_path / "panel.ifc")
    code, out, err = bim_cli(capsys, str(path), "--out", str(tmp_path / "o2"))
    assert code == 2
    assert (f"#{panel.id()} IfcPlate 'Panel W1': unsupported geometry: its geometry nests in "
            f"a loop (#{item.id()} -> #{item.id()})") in err
    code, out, err = bim_cli(capsys, str(path), "--out", str(tmp_path / "o3"),
                          "--skip-uninstallable")
    assert code == 0, err
    assert "5 elements to install" in out


def test_a_profile_curve_that_is_its_own_segment(tmp_path, capsys):
    b = three_rooms()
    f = b.file

    def pt(x: float, y: float) -> Any:
        return f.createIfcCartesianPoint((float(x), float(y)))

    outline = f.createIfcPolyline([pt(0, 0), pt(1200, 0), pt(1200, 20), pt(0, 20), pt(0, 0)])
    curve = f.createIfcCompositeCurve(
        [f.createIfcCompositeCurveSegment("CONTINUOUS", True, outline)], False)
    curve.Segments = [f.createIfcCompositeCurveSegment("CONTINUOUS", True, curve),
                      *curve.Segments]
    solid = f.createIfcExtrudedAreaSolid(
        f.createIfcArbitraryClosedProfileDef("AREA", None, curve),
        f.createIfcAxis2Placement3D(f.createIfcCartesianPoint((0.0, 0.0, 0.0))),
        f.createIfcDirection((0.0, 0.0, 1.0)), 300.0)
    rep = f.createIfcShapeRepresentation(b.body, "Body", "SweptSolid", [solid])
    panel = b.panels[0]
    panel.Representation = f.createIfcProductDefinitionShape(None, None, [rep])
    path = b.write(tmp_path / "curve.ifc")
    code, _, err = bim_cli(capsys, str(path), "--out", str(tmp_path / "o"))
    assert code == 2
    assert (f"#{panel.id()} IfcPlate 'Panel W1': unsupported geometry: its geometry nests in "
            f"a loop (#{curve.id()} -> #{curve.id()})") in err
