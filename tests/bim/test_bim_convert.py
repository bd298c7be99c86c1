"""bt-manip bim on generated buildings: the world, the door gaps, the schedule's order."""

from __future__ import annotations

import csv
import json
import math
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("ifcopenshell")

from ifc_buildings import PANELS, Panel, three_rooms

from bt_manip.bim.convert import BimOptions, convert
from bt_manip.cli import main
from bt_manip.sim.world_reader import parse_world


@pytest.fixture(scope="module")
def converted(tmp_path_factory: pytest.TempPathFactory):
    folder = tmp_path_factory.mktemp("bim")
    ifc = three_rooms().write(folder / "three_rooms.ifc")
    conversion = convert(BimOptions(ifc, folder / "out"))
    return ifc, conversion, parse_world(conversion.world_path)


def _wall(spec, name):
    return next(w for w in spec.walls if w.name == name)


def test_walls_and_door_gaps_in_metres(converted):
    _, _, spec = converted
    partition = _wall(spec, "partition")
    assert partition.start == pytest.approx((5.0, 0.0), abs=1e-3)
    assert partition.end == pytest.approx((5.0, 6.0), abs=1e-3)
    assert partition.thickness == pytest.approx(0.2, abs=1e-3)
    assert partition.height == pytest.approx(2.5, abs=1e-3)
    doors = [(d.at, d.width) for d in partition.doors]
    assert doors == [pytest.approx((1.5, 1.6), abs=1e-3), pytest.approx((4.5, 0.9), abs=1e-3)]
    assert _wall(spec, "north").doors == []
    assert {w.name for w in spec.walls} == {"south", "north", "west", "east", "partition", "store"}


def test_window_keeps_the_wall_below_and_above(converted):
    _, _, spec = converted
    south = _wall(spec, "south")
    assert [(d.at, d.width) for d in south.doors] == [pytest.approx((7.5, 1.2), abs=1e-3)]
    boxes = {b.name: b for b in spec.furniture}
    sill, lintel = boxes["south_sill_0"], boxes["south_lintel_0"]
    # sill from the floor to 0.9 m, lintel from 2.1 m to the top of the 2.5 m wall
    assert sill.parts[0].size == pytest.approx((1.2, 0.2, 0.9), abs=1e-3)
    assert sill.pose.xyz == pytest.approx((7.5, 0.0, 0.45), abs=1e-3)
    assert lintel.parts[0].size == pytest.approx((1.2, 0.2, 0.4), abs=1e-3)
    assert lintel.pose.xyz == pytest.approx((7.5, 0.0, 2.3), abs=1e-3)


def test_furniture_spaces_robot_and_stock(converted):
    _, conversion, spec = converted
    table = next(b for b in spec.furniture if b.name == "table")
    assert table.parts[0].size == pytest.approx((1.2, 0.8, 0.75), abs=1e-3)
    assert table.pose.xyz == pytest.approx((8.0, 5.0, 0.375), abs=1e-3)
    yaw = 2 * math.atan2(table.pose.quat[2], table.pose.quat[3])
    assert math.cos(2 * (yaw - math.radians(30))) == pytest.approx(1.0, abs=1e-6)
    assert {"workshop", "office", "store", "start", "stock"} <= set(spec.poses)
    office = spec.poses["office"]
    assert 5.1 < office.x < 9.9 and 0.1 < office.y < 2.9
    (robot,) = spec.robots
    assert robot.description == "husky_ur3"
    assert not robot.randomize.is_zero()
    # the robot starts in the largest space, the workshop (x 0..5, y 0..6)
    assert 0.0 < robot.pose.x < 5.0 and 0.0 < robot.pose.y < 6.0
    # every element waits in its own stand at the stock, in the workshop; the stock (stands,
    # elements and its pose) moves as one per seed
    assert [o.name for o in spec.objects] == [e.object for e in conversion.elements]
    for obj in spec.objects:
        assert 0.0 < obj.pose.xyz[0] < 5.0 and 0.0 < obj.pose.xyz[1] < 6.0
    stands = [b for b in spec.furniture if b.name.startswith("stand_")]
    assert len(stands) == 6
    (group,) = spec.groups
    assert set(group.members) == {o.name for o in spec.objects} | {s.name for s in stands} | {
        "stock"}
    assert not group.randomize.is_zero()


def test_targets_sizes_and_masses(converted):
    _, conversion, _ = converted
    by_name = {e.name: e for e in conversion.elements}
    for panel in PANELS:
        e = by_name[panel.name]
        t = e.target
        assert (t["x"], t["y"], t["z"]) == pytest.approx(panel.centre, abs=1e-3)
        assert math.cos(t["yaw"] - panel.yaw) == pytest.approx(1.0, abs=1e-6)
        assert e.size == pytest.approx([1.2, 0.02, 0.3], abs=1e-3)
        assert e.mass == pytest.approx(400 * 1.2 * 0.02 * 0.3, rel=1e-3)  # material's density
        assert e.ifc_class == "IfcPlate"
        assert e.task == f"Install {panel.name}"


def test_order_from_start_times(converted):
    _, conversion, _ = converted
    # no sequence: the tasks' starts (one working day apart) give the order
    assert [e.name for e in conversion.elements] == [p.name for p in PANELS]
    document = json.loads(conversion.schedule_path.read_text())
    assert [e["global_id"] for e in document["elements"]] == [
        e.global_id for e in conversion.elements
    ]
    assert document["elements"][0]["start"].startswith("2026-03-02")


def test_order_from_sequences(tmp_path):
    # a full chain against the starts: the sequence wins
    ifc = three_rooms(sequence=[5, 4, 3, 2, 1, 0]).write(tmp_path / "chain.ifc")
    c = convert(BimOptions(ifc, tmp_path / "chain"))
    assert [e.name for e in c.elements] == [p.name for p in reversed(PANELS)]
    # one link E1 -> W1: W1 waits for E1; the others go by start
    ifc = three_rooms(sequence=[3, 0]).write(tmp_path / "link.ifc")
    c = convert(BimOptions(ifc, tmp_path / "link"))
    names = [e.name for e in c.elements]
    assert names == ["Panel W2", "Panel W3", "Panel E1", "Panel W1", "Panel E2", "Panel S1"]


@pytest.mark.parametrize("element_class", ["IfcMember", "IfcWall"])
def test_elements_assigned_to_processes(tmp_path, element_class):
    ifc = three_rooms(link="process", element_class=element_class).write(tmp_path / "p.ifc")
    c = convert(BimOptions(ifc, tmp_path / "out"))
    assert [e.name for e in c.elements] == [p.name for p in PANELS]
    assert {e.ifc_class for e in c.elements} == {element_class}
    spec = parse_world(c.world_path)
    # walls to install are objects at the stock, not walls at their final place
    assert len(spec.walls) == 6 and len(spec.objects) == 6


def test_a_wall_read_by_the_geometry_kernel(tmp_path):
    import ifcopenshell.api

    b = three_rooms()
    f = b.file
    wall = ifcopenshell.api.run("root.create_entity", f, ifc_class="IfcWall", name="Mesh wall")
    # a 2 m x 0.1 m x 2 m box as a mesh, centred on its placement
    verts = [(x, y, z) for z in (0.0, 2.0) for x, y in ((-1, -0.05), (1, -0.05), (1, 0.05),
                                                        (-1, 0.05))]
    faces = [[0, 3, 2, 1], [4, 5, 6, 7], [0, 1, 5, 4], [1, 2, 6, 5], [2, 3, 7, 6], [3, 0, 4, 7]]
    rep = ifcopenshell.api.run("geometry.add_mesh_representation", f, context=b.body,
                               vertices=[verts], faces=[faces])
    ifcopenshell.api.run("geometry.assign_representation", f, product=wall, representation=rep)
    matrix = np.eye(4)
    matrix[:3, 3] = [7.5, 4.5, 0.0]
    ifcopenshell.api.run("geometry.edit_object_placement", f, product=wall, matrix=matrix)
    ifcopenshell.api.run("spatial.assign_container", f, products=[wall],
                         relating_structure=b.storey)
    c = convert(BimOptions(b.write(tmp_path / "k.ifc"), tmp_path / "out"))
    mesh = _wall(parse_world(c.world_path), "mesh_wall")
    assert sorted([mesh.start, mesh.end]) == [pytest.approx((6.5, 4.5), abs=1e-3),
                                              pytest.approx((8.5, 4.5), abs=1e-3)]
    assert mesh.thickness == pytest.approx(0.1, abs=1e-3)
    assert mesh.height == pytest.approx(2.0, abs=1e-3)


def test_order_from_csv(tmp_path):
    ifc = three_rooms(with_tasks=False).write(tmp_path / "b.ifc")
    # the same GlobalIds are not kept across generations: read them from this file
    import ifcopenshell

    model = ifcopenshell.open(str(ifc))
    gids = {p.Name: p.GlobalId for p in model.by_type("IfcPlate")}
    order = ["Panel E2", "Panel W1", "Panel S1", "Panel W3", "Panel E1", "Panel W2"]
    path = tmp_path / "schedule.csv"
    with path.open("w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["GlobalId", "start"])
        for i, name in enumerate(reversed(order)):
            w.writerow([gids[name], 100 - i])  # later rows start earlier
    c = convert(BimOptions(ifc, tmp_path / "csv", schedule=path))
    assert [e.name for e in c.elements] == order
    assert all(e.task is None for e in c.elements)


def test_ifc2x3_with_a_csv(tmp_path):
    ifc = three_rooms(schema="IFC2X3").write(tmp_path / "old.ifc")
    import ifcopenshell

    model = ifcopenshell.open(str(ifc))
    plates = model.by_type("IfcPlate")
    path = tmp_path / "s.csv"
    path.write_text("".join(f"{p.GlobalId},2026-04-0{i + 1}\n" for i, p in enumerate(plates[:2])))
    c = convert(BimOptions(ifc, tmp_path / "out", schedule=path))
    assert [e.name for e in c.elements] == [plates[0].Name, plates[1].Name]
    spec = parse_world(c.world_path)
    assert [(d.at, d.width) for d in _wall(spec, "partition").doors] == [
        pytest.approx((1.5, 1.6), abs=1e-3), pytest.approx((4.5, 0.9), abs=1e-3)]


def test_file_in_metres(tmp_path):
    ifc = three_rooms(mm=False).write(tmp_path / "m.ifc")
    c = convert(BimOptions(ifc, tmp_path / "out"))
    partition = _wall(parse_world(c.world_path), "partition")
    assert partition.end == pytest.approx((5.0, 6.0), abs=1e-3)
    assert (partition.doors[0].at, partition.doors[0].width) == pytest.approx((1.5, 1.6), abs=1e-3)
    assert c.elements[0].target["z"] == pytest.approx(0.15, abs=1e-3)


def test_command_line_writes_a_world_that_loads(tmp_path, capsys):
    from bt_manip.sim.world import World

    ifc = three_rooms().write(tmp_path / "b.ifc")
    assert main(["bim", str(ifc), "--out", str(tmp_path / "out"), "--stock", "2.8;3.55;1.5708",
                 "--start", "Office", "--seed-range", "0:2"]) == 0
    out = capsys.readouterr().out
    assert "6 elements to install" in out and "stock at (2.80, 3.55)" in out
    assert "loaded the world with seeds 0..1: every start is free" in out
    with World(tmp_path / "out" / "world.yaml", seed=3) as world:
        robot = world.summary()
        assert "robot robot (husky_ur3)" in robot
        panel = world.body_pose("panel_w1")
        # standing upright in its stand at the stock (moved with the stock for the seed)
        assert panel.xyz[2] == pytest.approx(0.15, abs=2e-3)
    spec = parse_world(tmp_path / "out" / "world.yaml")
    start = spec.robots[0].pose
    assert 5.0 < start.x < 10.0 and 0.0 < start.y < 3.0  # in the office


def test_elements_in_a_panel_list_can_be_changed():
    b = three_rooms(panels=[Panel("Only", (0.11, 3.0, 1.0), math.pi / 2, "2026-03-02")])
    assert len(b.panels) == 1 and len(b.tasks) == 1


NAVIGATE = """<root BTCPP_format="4" main_tree_to_execute="Main">
  <BehaviorTree ID="Main">
    <Sequence>
      <Navigate goal="office"/>
      <Navigate goal="stock"/>
    </Sequence>
  </BehaviorTree>
</root>
"""


@pytest.mark.slow
def test_the_robot_drives_through_the_generated_doors(tmp_path, converted):
    # from the workshop through the 1.6 m door to the office, and back to the stock's apron
    _, conversion, _ = converted
    tree = tmp_path / "nav.xml"
    tree.write_text(NAVIGATE)
    report = tmp_path / "report.json"
    code = main(["run", str(tree), "--world", str(conversion.world_path), "--seed", "1",
                 "--quiet", "--report", str(report)])
    assert code == 0
    assert json.loads(report.read_text())["status"] == "SUCCESS"


def test_mitred_wall_ends_are_read():
    from bt_manip.bim.shapes import Solid, footprint_box, is_box_like

    # a 1 m x 0.3 m x 2.5 m wall cut at 45 degrees at both ends (a trapezoid in plan)
    plan = [(0.0, 0.0), (1.0, 0.0), (0.7, 0.3), (0.3, 0.3)]
    points = np.array([(x, y, z) for z in (0.0, 2.5) for x, y in plan])
    box = footprint_box(points)
    assert box.size == pytest.approx((1.0, 0.3, 2.5))
    assert is_box_like(Solid(points, volume=(1.0 + 0.4) / 2 * 0.3 * 2.5), box)
    # a square post with one corner cut off (12.5 % of its box missing) is not a box
    post = np.array([(x, y, z) for z in (0.0, 2.5) for x, y in
                     [(0, 0), (0.6, 0), (0.6, 0.3), (0.3, 0.6), (0, 0.6)]])
    volume = (0.6 * 0.6 - 0.3 * 0.3 / 2) * 2.5
    assert not is_box_like(Solid(post, volume=volume), footprint_box(post))


def test_schedule_follows_its_json_schema(converted):
    jsonschema = pytest.importorskip("jsonschema")
    root = Path(__file__).resolve().parents[2]
    schema = json.loads((root / "docs" / "schemas" / "bim-schedule.schema.json").read_text())
    _, conversion, _ = converted
    document = json.loads(conversion.schedule_path.read_text())
    jsonschema.validate(document, schema)
    broken = {**document, "elements": [{**document["elements"][0], "mass": -1}]}
    with pytest.raises(jsonschema.ValidationError):
        jsonschema.validate(broken, schema)


@pytest.mark.parametrize("enabled", [True, False])
def test_the_cycle_collector_is_paused_and_left_as_it_was(tmp_path, monkeypatch, enabled):
    import gc

    import bt_manip.bim.convert as convert_module
    from bt_manip.errors import InputError

    seen: list[bool] = []
    reading = convert_module.read_building

    def read_building(*args, **kwargs):
        seen.append(gc.isenabled())
        return reading(*args, **kwargs)

    monkeypatch.setattr(convert_module, "read_building", read_building)
    ifc = three_rooms().write(tmp_path / "rooms.ifc")
    broken = tmp_path / "broken.ifc"
    broken.write_text("ISO-10303-21;\nHEADER;\nENDSEC;\n")
    was = gc.isenabled()
    try:
        gc.enable() if enabled else gc.disable()
        convert(BimOptions(ifc, tmp_path / "out"))
        assert gc.isenabled() is enabled
        with pytest.raises(InputError):
            convert(BimOptions(broken, tmp_path / "broken"))
        assert gc.isenabled() is enabled
    finally:
        gc.enable() if was else gc.disable()
    assert seen == [False]
