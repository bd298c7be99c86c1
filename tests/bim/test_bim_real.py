"""Real buildings become worlds: the sample exports of ../shared, and generated buildings with
what real exports hold (holed wall bodies, curtain walls, gables, walls without body)."""

from __future__ import annotations

import itertools
import json
import math
from pathlib import Path

import pytest
import yaml

pytest.importorskip("ifcopenshell")

import ifcopenshell
import ifcopenshell.util.element as util
from ifc_buildings import HOLE, PANELS, WINDOW, Panel, real_features, stepped_top, three_rooms

from bt_manip.bim.convert import BimOptions, convert
from bt_manip.bim.ifc_input import open_ifc
from bt_manip.cli import main
from bt_manip.sim.world_reader import parse_world

SAMPLES = Path("../shared/samples/ifc")
SAMPLE_FILES = ["Example_Import_IFC.ifc", "modelo2016.ifc", "web-ifc-viewer_test.ifc"]


def _sample(name: str) -> Path:
    path = SAMPLES / name
    if not path.is_file():
        pytest.skip(f"{path} is absent (the shared samples are read relative to the project root)")
    return path


def _storey(el):
    current = util.get_container(el) or util.get_aggregate(el)
    while current is not None and not current.is_a("IfcBuildingStorey"):
        current = util.get_container(current) or util.get_aggregate(current)
    return current


def test_line_numbers_come_from_one_index(tmp_path):
    path = three_rooms().write(tmp_path / "b.ifc")
    source = open_ifc(path)
    lines = path.read_text().splitlines()
    expected = {int(t.split("=")[0][1:]): i for i, t in enumerate(lines, 1) if t.startswith("#")}
    ids = sorted(expected)
    for step_id in ids[:5] + ids[-5:]:  # searched one by one, then all indexed at once
        assert source.line_of(step_id) == expected[step_id]
    assert source.line_of(ids[-1] + 1000) is None
    assert all(source.line_of(i) == expected[i] for i in ids)


@pytest.mark.parametrize("name", SAMPLE_FILES)
def test_sample_buildings_become_worlds_with_ifcopenshells_counts(name, tmp_path):
    path = _sample(name)
    c = convert(BimOptions(path, tmp_path / "out"))
    model = ifcopenshell.open(str(path))
    storeys = model.by_type("IfcBuildingStorey")
    ground = min(storeys, key=lambda s: abs(float(s.Elevation or 0.0)))
    assert c.storey == ground.Name

    def on(cls: str) -> list:
        return [e for e in model.by_type(cls) if (s := _storey(e)) is not None and s == ground]

    counts = c.building.counts
    assert counts["walls"] == len(on("IfcWall"))
    assert counts["doors"] == len(on("IfcDoor"))
    assert counts["windows"] == len(on("IfcWindow"))
    assert counts["curtain walls"] == len(on("IfcCurtainWall"))
    parts = [p for cw in on("IfcCurtainWall") for rel in cw.IsDecomposedBy
             for p in rel.RelatedObjects]
    assert counts["plates"] == sum(1 for p in parts if p.is_a("IfcPlate"))
    assert counts["members"] == sum(1 for p in parts if p.is_a("IfcMember"))
    text = c.summary()
    def n(key: str) -> str:  # the count and its noun, singular for one
        return f"{counts[key]} {key[:-1] if counts[key] == 1 else key}"

    assert (f"{n('walls')}, {n('curtain walls')} ({n('plates')}, {n('members')}), "
            f"{n('doors')}, {n('windows')}") in text
    # the world alone: nothing is scheduled in these exports
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == ["world.yaml"]
    spec = parse_world(c.world_path)
    assert spec.walls and any(w.doors for w in spec.walls)


def test_web_ifc_curtain_wall_closes_the_facade(tmp_path):
    c = convert(BimOptions(_sample("web-ifc-viewer_test.ifc"), tmp_path / "out"))
    assert c.building.counts["curtain walls"] == 1
    assert c.building.counts["plates"] == 12 and c.building.counts["members"] == 31
    assert len(c.building.curtain_walls) >= 4  # the plates and members within the band
    names = {f.name for f in parse_world(c.world_path).furniture}
    assert {f.name for f in c.building.curtain_walls} <= names


def test_storey_by_name_and_index(tmp_path, capsys):
    path = _sample("Example_Import_IFC.ifc")
    assert main(["bim", str(path), "--out", str(tmp_path / "a"), "--storey", "2"]) == 0
    assert "storey 'Level 2' (elevation 3.10 m, index 2 of --storey" in capsys.readouterr().out
    assert main(["bim", str(path), "--out", str(tmp_path / "b"), "--storey", "Level 2"]) == 0
    assert "storey 'Level 2' (elevation 3.10 m, given with --storey" in capsys.readouterr().out
    assert main(["bim", str(path), "--out", str(tmp_path / "c"), "--storey", "9"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("--storey: no storey named or numbered '9'; storeys: 0 'T/FDN'")


def test_nothing_to_install_is_an_error_only_when_required(tmp_path, capsys):
    path = _sample("Example_Import_IFC.ifc")
    assert main(["bim", str(path), "--out", str(tmp_path / "o"), "--require-install"]) == 2
    err = capsys.readouterr().err
    assert "#23515 IfcProject '0001': no element to install" in err
    assert not (tmp_path / "o").exists()


def _far_spaces(world: Path) -> tuple[str, str]:
    spec = parse_world(world)
    spaces = [k for k in spec.poses if k not in ("start",)]
    return max(itertools.combinations(spaces, 2),
               key=lambda ab: math.dist(spec.poses[ab[0]][:2], spec.poses[ab[1]][:2]))


def _navigate(tmp_path: Path, world: Path, a: str, b: str) -> dict:
    tree = tmp_path / "nav.xml"
    tree.write_text(f"""<root BTCPP_format="4" main_tree_to_execute="Main">
  <BehaviorTree ID="Main">
    <Sequence>
      <Navigate goal="{a}"/>
      <Navigate goal="{b}"/>
    </Sequence>
  </BehaviorTree>
</root>
""")
    report = tmp_path / "report.json"
    code = main(["run", str(tree), "--world", str(world), "--seed", "0", "--quiet",
                 "--report", str(report)])
    data = json.loads(report.read_text())
    assert code == 0, data.get("reason")
    return data


@pytest.mark.slow
def test_navigate_between_the_farthest_spaces_of_a_real_building(tmp_path):
    c = convert(BimOptions(_sample("Example_Import_IFC.ifc"), tmp_path / "out"))
    a, b = _far_spaces(c.world_path)
    spec = parse_world(c.world_path)
    assert math.dist(spec.poses[a][:2], spec.poses[b][:2]) > 10.0  # across the house
    assert _navigate(tmp_path, c.world_path, a, b)["status"] == "SUCCESS"


@pytest.fixture(scope="module")
def real(tmp_path_factory: pytest.TempPathFactory):
    folder = tmp_path_factory.mktemp("real")
    b = real_features(three_rooms())
    path = b.write(folder / "real.ifc")
    return b, path, convert(BimOptions(path, folder / "out"))


def test_holed_wall_curtain_wall_gable_and_bodiless_wall(real):
    b, _, c = real
    store = next(w for w in c.building.walls if w.name == "store")
    (hole,) = store.openings
    assert hole.kind == "hole" and hole.passage
    assert (hole.start + 5.0, hole.end + 5.0, hole.top) == pytest.approx(HOLE, abs=0.01)
    spec = parse_world(c.world_path)
    (door,) = next(w for w in spec.walls if w.name == "store").doors
    assert door.at + 5.0 == pytest.approx((HOLE[0] + HOLE[1]) / 2, abs=0.01)
    assert {f.name for f in c.building.curtain_walls} == {
        "glass_0", "glass_1", "mullion_0", "mullion_1", "mullion_2"}
    skipped = dict(c.building.skipped)
    gable, sketch = b.walls["Gable"], b.walls["Sketch"]
    assert skipped[f"#{gable.id()} IfcWall 'Gable'"].startswith("above the robot's height band")
    assert skipped[f"#{sketch.id()} IfcWall 'Sketch'"] == (
        "it has no body geometry (no 'Body' representation)")
    assert c.building.counts == {"walls": 8, "curtain walls": 1, "plates": 2, "members": 3,
                                 "doors": 2, "windows": 1, "other obstacles": 1}
    assert len(c.elements) == 6  # every panel still installable


def test_a_wall_top_stepping_down_is_no_opening(tmp_path):
    # a wall under a sloping roof: its body's top is lower along part of it; only the window
    # cut into the body is an opening, not the strip above the lower top, nor both merged
    path = stepped_top(three_rooms(with_tasks=False)).write(tmp_path / "stepped.ifc")
    c = convert(BimOptions(path, tmp_path / "out"))
    store = next(w for w in c.building.walls if w.name == "store")
    (window,) = store.openings
    assert window.kind == "hole" and not window.passage
    x0, x1, z0, z1 = WINDOW
    assert (window.start + 5.0, window.end + 5.0, window.bottom, window.top) == pytest.approx(
        (x0, x1, z0, z1), abs=0.01)
    spec = parse_world(c.world_path)
    wall = next(w for w in spec.walls if w.name == "store")
    # the window's gap in the wall, filled below and above by a sill and a lintel
    (gap,) = wall.doors
    assert (gap.at + 5.0, gap.width) == pytest.approx(((x0 + x1) / 2, x1 - x0), abs=0.01)
    assert wall.height == pytest.approx(2.5, abs=0.01)
    furniture = yaml.safe_load(c.world_path.read_text())["furniture"]
    (sill,) = [f for f in furniture if f["name"].startswith("store_sill")]
    (lintel,) = [f for f in furniture if f["name"].startswith("store_lintel")]
    assert sill["size"][2] == pytest.approx(z0, abs=0.01)
    assert lintel["pose"]["xyz"][2] - lintel["size"][2] / 2 == pytest.approx(z1, abs=0.01)


@pytest.mark.slow
def test_navigate_through_a_hole_in_a_wall_body(tmp_path):
    # without tasks: the building alone, no stock in the way
    path = real_features(three_rooms(with_tasks=False)).write(tmp_path / "real.ifc")
    c = convert(BimOptions(path, tmp_path / "out"))
    a, b = _far_spaces(c.world_path)
    assert _navigate(tmp_path, c.world_path, "office", "store")["status"] == "SUCCESS"
    assert _navigate(tmp_path, c.world_path, a, b)["status"] == "SUCCESS"


def _too_high_and_too_thick():
    panels = [*PANELS[:2],
              Panel("Panel High", (0.19, 5.0, 0.86), math.pi / 2, "2026-03-10")]
    b = three_rooms(panels=panels)
    return b


def test_an_element_the_robot_cannot_grasp_is_refused(tmp_path, capsys):
    b = _too_high_and_too_thick()
    path = b.write(tmp_path / "b.ifc")
    high = b.panels[-1]
    assert main(["bim", str(path), "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert f"#{high.id()} IfcPlate 'Panel High': its top edge where it is placed, 1.01 m above " \
           "the floor, is out of the husky_ur3's reach for a grasp from above" in err
    assert not (tmp_path / "o").exists()
    assert main(["bim", str(path), "--out", str(tmp_path / "o"), "--skip-uninstallable"]) == 0
    out = capsys.readouterr().out
    assert "refused: IfcPlate 'Panel High'" in out
    document = json.loads((tmp_path / "o" / "schedule.json").read_text())
    assert [e["name"] for e in document["elements"]] == ["Panel W1", "Panel W2"]
    (refused,) = document["refused"]
    assert refused["global_id"] == high.GlobalId and "out of the husky_ur3's reach" in refused[
        "reason"]
    assert (tmp_path / "o" / "install.xml").is_file()
    jsonschema = pytest.importorskip("jsonschema")
    root = Path(__file__).resolve().parents[2]
    schema = json.loads((root / "docs" / "schemas" / "bim-schedule.schema.json").read_text())
    jsonschema.validate(document, schema)


def test_a_partition_thicker_than_the_gripper_opens_is_refused(tmp_path, capsys):
    b = three_rooms(with_tasks=False)
    thick = b.walls["Store"]  # 0.2 m thick
    path = b.write(tmp_path / "b.ifc")
    csv = tmp_path / "s.csv"
    csv.write_text(f"{thick.GlobalId},1\n")
    assert main(["bim", str(path), "--out", str(tmp_path / "o"), "--schedule", str(csv)]) == 2
    err = capsys.readouterr().err
    assert "20.0 cm thick, too thick for the husky_ur3's gripper, which opens 10.0 cm" in err
    assert main(["bim", str(path), "--out", str(tmp_path / "o"), "--schedule", str(csv),
                 "--skip-uninstallable", "--png", str(tmp_path / "top.png")]) == 0
    out = capsys.readouterr().out
    assert "0 elements to install" in out and f"wrote {tmp_path / 'top.png'}" in out
    assert ("note: nothing to install: every element was refused (schedule.json's 'refused' "
            "lists each with its reason); the world holds the building alone") in out
    assert "--require-install" not in out
    assert (tmp_path / "top.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert json.loads((tmp_path / "o" / "schedule.json").read_text())["elements"] == []
    assert not (tmp_path / "o" / "install.xml").exists()
    assert main(["bim", str(path), "--out", str(tmp_path / "p"), "--schedule", str(csv),
                 "--skip-uninstallable", "--require-install"]) == 2
    assert "every element was refused" in capsys.readouterr().err
