"""Every problem of a building model as ``file:line: #id IfcClass 'Name': message``, exit 2."""

from __future__ import annotations

import math
import re
import sys
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("ifcopenshell")

import ifcopenshell.api
from ifc_buildings import PANELS, Panel, three_rooms

from bt_manip.cli import main
from bt_manip.sim.world_reader import parse_world


def _run(capsys, *argv: str) -> tuple[int, str]:
    code = main(["bim", *argv])
    captured = capsys.readouterr()
    assert "Traceback" not in captured.err
    return code, captured.err


def _line_of(path: Path, step_id: int) -> int:
    for i, line in enumerate(path.read_text().splitlines(), start=1):
        if line.startswith(f"#{step_id}="):
            return i
    raise AssertionError(f"#{step_id} not in {path}")


def test_not_an_ifc_file(tmp_path, capsys):
    bad = tmp_path / "notes.ifc"
    bad.write_text("walls: 3\n")
    code, err = _run(capsys, str(bad), "--out", str(tmp_path / "o"))
    assert code == 2
    assert err.strip() == f"{bad}:1: not an IFC file: it does not start with 'ISO-10303-21;'"


def test_a_file_holding_no_spatial_structure(tmp_path, capsys):
    # no storey, building, site or project: nothing stands for a level to build
    f = ifcopenshell.file(schema="IFC4")
    f.createIfcWall(ifcopenshell.guid.new(), None, "Alone")
    path = tmp_path / "bare.ifc"
    f.write(str(path))
    code, err = _run(capsys, str(path), "--out", str(tmp_path / "o"))
    assert code == 2
    assert err.strip().endswith(
        "no IfcBuildingStorey, IfcBuilding, IfcSite or IfcProject: nothing to build a world from")
    assert err.strip().startswith(f"{path}")


def test_unsupported_geometry_of_a_round_wall(tmp_path, capsys):
    # a round wall to install is refused; the same wall as part of the building is an obstacle
    b = three_rooms(with_tasks=False)
    f = b.file
    wall = ifcopenshell.api.run("root.create_entity", f, ifc_class="IfcWall", name="Round")
    profile = f.createIfcCircleProfileDef("AREA", None, None, 300.0)
    rep = ifcopenshell.api.run("geometry.add_profile_representation", f, context=b.body,
                               profile=profile, depth=2.5)
    ifcopenshell.api.run("geometry.assign_representation", f, product=wall, representation=rep)
    matrix = np.eye(4)
    matrix[:3, 3] = [2.5, 3.0, 0.0]  # metres: the api converts to the file's millimetres
    ifcopenshell.api.run("geometry.edit_object_placement", f, product=wall, matrix=matrix)
    ifcopenshell.api.run("spatial.assign_container", f, products=[wall],
                         relating_structure=b.storey)
    path = b.write(tmp_path / "round.ifc")
    csv = tmp_path / "s.csv"
    csv.write_text(f"{wall.GlobalId},1\n")
    code, err = _run(capsys, str(path), "--out", str(tmp_path / "o"), "--schedule", str(csv))
    assert code == 2
    line = _line_of(path, wall.id())
    prefix = f"{path}:{line}: #{wall.id()} IfcWall 'Round': unsupported geometry:"
    assert err.startswith(prefix)
    # a 0.3 m circle fills about pi/4 of its square
    m = re.search(r"fills (\d+)% of its upright bounding box \(0.600 x 0.600 x 2.500 m\)", err)
    assert m is not None and 75 <= int(m.group(1)) < 90, err
    assert not (tmp_path / "o").exists()

    code, _ = _run(capsys, str(path), "--out", str(tmp_path / "world"))
    assert code == 0
    spec = parse_world(tmp_path / "world" / "world.yaml")
    (round_wall,) = [item for item in spec.furniture if item.name == "round"]
    assert len(round_wall.parts) > 3  # strips across the circle
    centre = np.array(round_wall.pose.xyz[:2])
    assert centre == pytest.approx((2.5, 3.0), abs=0.01)
    for part in round_wall.parts:  # every strip within the circle's square, none far outside
        assert abs(part.xyz[0]) + part.size[0] / 2 <= 0.31
        assert abs(part.xyz[1]) + part.size[1] / 2 <= 0.31
        assert part.size[2] == pytest.approx(2.5, abs=1e-3)
    # the strips cover the circle, and less than its square
    area = sum(p.size[0] * p.size[1] for p in round_wall.parts)
    assert math.pi * 0.3**2 <= area < 0.95 * 0.6**2


def test_element_wider_than_the_doors_on_its_route(tmp_path, capsys):
    # a panel for the store, which only the 0.9 m door joins to the rest
    panels = [*PANELS[:5], Panel("Panel S1", (9.81, 4.5, 0.15), -math.pi / 2, "2026-03-10")]
    b = three_rooms(panels=panels)
    path = b.write(tmp_path / "store.ifc")
    panel = b.panels[-1]
    # a stock that leaves the way to the store's door open
    code, err = _run(capsys, str(path), "--out", str(tmp_path / "o"), "--stock", "2.8;3.55;1.5708")
    assert code == 2
    assert err.strip() == (
        f"{path}:{_line_of(path, panel.id())}: #{panel.id()} IfcPlate 'Panel S1': 1.20 m long, "
        "it needs a passage 1.30 m wide when carried, wider than any door on its route; its "
        "route from the stock passes the 0.90 m door of wall 'Partition' at (5.00, 4.50)"
    )


def test_unreachable_place(tmp_path, capsys):
    # outside the building, which has no door to the outside (standing on the ground, within
    # the arm's reach)
    panels = [*PANELS[:2], Panel("Panel X", (12.0, 3.0, 0.15), 0.0, "2026-03-10")]
    b = three_rooms(panels=panels)
    path = b.write(tmp_path / "outside.ifc")
    panel = b.panels[-1]
    code, err = _run(capsys, str(path), "--out", str(tmp_path / "o"))
    assert code == 2
    assert err.strip() == (
        f"{path}:{_line_of(path, panel.id())}: #{panel.id()} IfcPlate 'Panel X': its place "
        "(12.00, 3.00) cannot be reached: no route for the robot joins the stock to it"
    )


def test_schedule_naming_unknown_global_ids(tmp_path, capsys):
    b = three_rooms(with_tasks=False)
    path = b.write(tmp_path / "b.ifc")
    csv = tmp_path / "s.csv"
    slab = b.file.by_type("IfcSlab")[0]
    csv.write_text(
        f"GlobalId,start\n{b.panels[0].GlobalId},1\n0000000000000000000000,2\n{slab.GlobalId},3\n"
    )
    code, err = _run(capsys, str(path), "--out", str(tmp_path / "o"), "--schedule", str(csv))
    assert code == 2
    assert err.splitlines() == [
        f"{csv}:3: unknown GlobalId '0000000000000000000000': no entity of b.ifc has it",
        f"{csv}:4: GlobalId '{slab.GlobalId}' is #{slab.id()} IfcSlab 'Ground slab'; only "
        "IfcPlate, IfcMember and IfcWall elements are installed",
    ]


def test_ifc2x3_needs_a_csv(tmp_path, capsys):
    b = three_rooms(schema="IFC2X3")
    path = b.write(tmp_path / "old.ifc")
    code, err = _run(capsys, str(path), "--out", str(tmp_path / "o"), "--require-install")
    assert code == 2
    assert "no element to install: schedules are read from IFC4 files only" in err
    assert "--schedule FILE.csv" in err
    assert not (tmp_path / "o").exists()
    # without --require-install, the building alone becomes a world, and the note says why
    code = main(["bim", str(path), "--out", str(tmp_path / "w")])
    out = capsys.readouterr().out
    assert code == 0
    assert "no element to install: schedules are read from IFC4 files only" in out
    assert sorted(p.name for p in (tmp_path / "w").iterdir()) == ["world.yaml"]
    spec = parse_world(tmp_path / "w" / "world.yaml")
    assert {"workshop", "office", "store", "start"} <= set(spec.poses)
    assert spec.objects == [] and len(spec.walls) == 6


def test_file_and_element_count_bounds(tmp_path, capsys, monkeypatch):
    import bt_manip.bim.building as building
    import bt_manip.bim.ifc_input as ifc_input

    path = three_rooms().write(tmp_path / "b.ifc")
    monkeypatch.setattr(ifc_input, "MAX_IFC_BYTES", 1000)
    code, err = _run(capsys, str(path), "--out", str(tmp_path / "o"))
    assert code == 2 and err.strip() == f"{path}: IFC file is larger than the limit of 1000 bytes"
    monkeypatch.undo()
    monkeypatch.setattr(building, "MAX_WALLS", 3)
    code, err = _run(capsys, str(path), "--out", str(tmp_path / "o"))
    assert code == 2
    assert err.strip() == f"{path}: the file holds 6 IfcWall entities, more than the limit of 3"


def test_without_ifcopenshell_says_how_to_install(tmp_path, capsys, monkeypatch):
    path = three_rooms().write(tmp_path / "b.ifc")
    monkeypatch.setitem(sys.modules, "ifcopenshell", None)
    code, err = _run(capsys, str(path), "--out", str(tmp_path / "o"))
    assert code == 2
    assert "pip install 'bt-manip[bim]'" in err


def test_stock_on_a_wall(tmp_path, capsys):
    path = three_rooms().write(tmp_path / "b.ifc")
    code, err = _run(capsys, str(path), "--out", str(tmp_path / "o"), "--stock", "5;3;0")
    assert code == 2
    assert err.startswith("--stock: the stock area") and "overlaps a wall" in err


def test_element_on_another_storey(tmp_path, capsys):
    b = three_rooms()
    f = b.file
    upper = ifcopenshell.api.run("root.create_entity", f, ifc_class="IfcBuildingStorey",
                                 name="First floor")
    ifcopenshell.api.run("aggregate.assign_object", f, products=[upper],
                         relating_object=f.by_type("IfcBuilding")[0])
    panel = b.panels[0]
    ifcopenshell.api.run("spatial.assign_container", f, products=[panel],
                         relating_structure=upper)
    path = b.write(tmp_path / "two.ifc")
    code, err = _run(capsys, str(path), "--out", str(tmp_path / "o"))
    assert code == 2
    assert err.strip() == (
        f"{path}:{_line_of(path, panel.id())}: #{panel.id()} IfcPlate 'Panel W1': it is on "
        "storey 'First floor'; the world is built from storey 'Ground floor' (the one holding "
        "the most walls) only"
    )


def test_sequence_cycle(tmp_path, capsys):
    b = three_rooms(sequence=[0, 1])  # W1 before W2, and (below) W2 before W1
    import ifcopenshell.guid

    b.file.create_entity("IfcRelSequence", GlobalId=ifcopenshell.guid.new(),
                         RelatingProcess=b.tasks[1], RelatedProcess=b.tasks[0],
                         SequenceType="FINISH_START")
    path = b.write(tmp_path / "cycle.ifc")
    code, err = _run(capsys, str(path), "--out", str(tmp_path / "o"))
    assert code == 2
    rels = [r for r in b.file.by_type("IfcRelSequence") if r.RelatedProcess == b.tasks[0]]
    (rel,) = rels
    assert err.strip() == (
        f"{path}:{_line_of(path, rel.id())}: #{rel.id()} IfcRelSequence: the task sequences "
        "form a cycle: no order satisfies them all"
    )


def test_schedule_rows_with_bad_starts_and_duplicates(tmp_path, capsys):
    b = three_rooms(with_tasks=False)
    path = b.write(tmp_path / "b.ifc")
    g0, g1 = b.panels[0].GlobalId, b.panels[1].GlobalId
    csv = tmp_path / "s.csv"
    csv.write_text(f"{g0},2026-03-02\n{g1},next monday\n{g0},2026-03-04\n{g1}\n")
    code, err = _run(capsys, str(path), "--out", str(tmp_path / "o"), "--schedule", str(csv))
    assert code == 2
    assert err.splitlines() == [
        f"{csv}:2: start 'next monday' is neither a number nor an ISO 8601 date or date-time",
        f"{csv}:3: GlobalId '{g0}' is listed twice (first at line 1)",
        f"{csv}:4: expected 'GlobalId,start', got 1 fields",
    ]
