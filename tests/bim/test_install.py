"""From a building model to an installation run: install.xml, Place, Fasten, as-built, plot."""

from __future__ import annotations

import json
import math
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

pytest.importorskip("ifcopenshell")

from ifc_buildings import PANELS, three_rooms

from bt_manip.bim.convert import BimOptions, convert
from bt_manip.cli import main


@pytest.fixture(scope="module")
def two_panels(tmp_path_factory: pytest.TempPathFactory):
    """Panels W2 and W3 before the workshop's west wall, converted, and installed (seed 0)."""
    folder = tmp_path_factory.mktemp("install")
    ifc = three_rooms(panels=[PANELS[1], PANELS[2]]).write(folder / "two.ifc")
    conversion = convert(BimOptions(ifc, folder / "out"))
    report = folder / "report.json"
    bb = folder / "bb.json"
    code = main(["run", str(conversion.install_path), "--world", str(conversion.world_path),
                 "--seed", "0", "--quiet", "--report", str(report), "--bb-out", str(bb)])
    return conversion, code, json.loads(report.read_text()), json.loads(bb.read_text()), report


def _reasons(report: dict, name: str) -> list[str]:
    return [n["reason"] for n in report["nodes"] if n["path"].endswith("/" + name)]


def test_install_tree_is_valid_and_in_schedule_order(two_panels, capsys):
    conversion, *_ = two_panels
    assert main(["validate", str(conversion.install_path)]) == 0
    assert "OK" in capsys.readouterr().out
    root = ET.parse(conversion.install_path).getroot()
    main_tree = root.find("BehaviorTree[@ID='Install']")
    assert main_tree is not None
    calls = main_tree.findall(".//SubTree[@ID='InstallElement']")
    assert [c.get("element") for c in calls] == [e.object for e in conversion.elements]
    for call, e in zip(calls, conversion.elements, strict=True):
        t = e.target
        x, y, z, yaw = (float(v) for v in call.get("target", "").split(";"))
        assert (x, y, z, yaw) == pytest.approx((t["x"], t["y"], t["z"], t["yaw"]), abs=1e-4)
        assert call.get("global_id") == e.global_id
        assert call.get("deviation_mm") == f"{{deviation_mm_{e.object}}}"
    place = root.find("BehaviorTree[@ID='PlaceElement']")
    assert place is not None
    ids = [n.tag for n in place.iter()]
    assert ids.index("PlanBaseForPlace") < ids.index("Place") < ids.index("Fasten") < ids.index(
        "Detach")


@pytest.mark.slow
def test_two_panels_installed_in_order_within_tolerance(two_panels):
    conversion, code, report, bb, _ = two_panels
    assert code == 0 and report["status"] == "SUCCESS"
    assert bb["installed"] == 2 and bb["to_install"] == 0
    rows = report["as_built"]
    assert [r["global_id"] for r in rows] == [e.global_id for e in conversion.elements]
    for row, e in zip(rows, conversion.elements, strict=True):
        assert row["status"] == "installed"
        assert row["fastened_to"] == "ground"
        assert row["planned"] == pytest.approx(
            [e.target["x"], e.target["y"], e.target["z"], e.target["yaw"]], abs=1e-4)
        # within 2 cm and 2 deg of the BIM pose, as Place and Fasten checked
        assert row["deviation_mm"] <= 20.0 and row["deviation_deg"] <= 2.0
        assert math.dist(row["placed"][:3], row["planned"][:3]) * 1000 == pytest.approx(
            row["deviation_mm"], abs=0.2)
        assert bb[f"deviation_mm_{e.object}"] <= 20.0
        assert bb[f"deviation_deg_{e.object}"] <= 2.0
    # Place succeeded only because the panel touched nothing before its final motion
    placed = _reasons(report, "place_element")
    assert all(r.startswith("placed 'panel_w") for r in placed)


def test_the_report_with_its_as_built_table_follows_the_schema(two_panels):
    jsonschema = pytest.importorskip("jsonschema")
    root = Path(__file__).resolve().parents[2]
    schema = json.loads((root / "docs" / "schemas" / "run-report.schema.json").read_text())
    report = two_panels[2]
    jsonschema.Draft202012Validator(schema).validate(report)
    broken = {**report, "as_built": [{**report["as_built"][0], "status": "done"}]}
    with pytest.raises(jsonschema.ValidationError):
        jsonschema.Draft202012Validator(schema).validate(broken)


def test_bim_report_draws_the_floor_plan(two_panels, tmp_path, capsys):
    *_, report_path = two_panels
    png = tmp_path / "as_built.png"
    assert main(["bim-report", str(report_path), "--png", str(png)]) == 0
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    out = capsys.readouterr().out
    assert "Panel W2" in out and "Panel W3" in out and f"wrote {png}" in out


def test_bim_report_needs_an_as_built_table(tmp_path, capsys):
    report = tmp_path / "plain.json"
    report.write_text(json.dumps({"status": "SUCCESS", "nodes": []}))
    assert main(["bim-report", str(report), "--png", str(tmp_path / "x.png")]) == 2
    err = capsys.readouterr().err
    assert err.strip() == (
        f"{report}: no as_built table: it is written by `bt-manip run --report` in a world "
        "made by `bt-manip bim`"
    )
    assert not (tmp_path / "x.png").exists()


CHECKS = """<root BTCPP_format="4" main_tree_to_execute="Checks">
  <BehaviorTree ID="Checks">
    <Sequence>
      <ForceSuccess>
        <Place name="place_not_held" object="panel_w2" target="{target}"/>
      </ForceSuccess>
      <SubTree ID="FetchElement" element="panel_w2" opening="0.021"/>
      <ForceSuccess>
        <Place name="place_far" object="panel_w2" target="8.0;5.0;0.15;0"/>
      </ForceSuccess>
      <PlanBaseForPlace object="panel_w2" target="{target}" base_pose="{b}" staging_pose="{s}"/>
      <Navigate goal="{s}" xy_tolerance="0.08" yaw_tolerance="0.08"/>
      <DriveStraight goal="{b}" xy_tolerance="0.04" yaw_tolerance="0.08"/>
      <ForceSuccess>
        <Place name="place_tight" object="panel_w2" target="{target}" position_tolerance="0.0005"
               deviation_mm="{dev_mm}"/>
      </ForceSuccess>
      <ForceSuccess>
        <Fasten name="fasten_off" object="panel_w2" target="{off_target}"/>
      </ForceSuccess>
      <Fasten name="fasten_ok" object="panel_w2" target="{target}" fastened_to="{to}"/>
      <ForceSuccess><Fasten name="fasten_again" object="panel_w2" target="{target}"/></ForceSuccess>
    </Sequence>
  </BehaviorTree>
  FETCH
</root>
"""

TOUCH = """<root BTCPP_format="4" main_tree_to_execute="Touch">
  <BehaviorTree ID="Touch">
    <Sequence>
      <SubTree ID="FetchElement" element="panel_w2" opening="0.021"/>
      <ForceSuccess><MoveToolBy name="push_down" offset="0;0;-0.3" CHECK/></ForceSuccess>
      <Place name="place_touched" object="panel_w2" target="{target}"/>
    </Sequence>
  </BehaviorTree>
  FETCH
</root>
"""


def _with_fetch(text: str, install: Path) -> str:
    fetch = ET.parse(install).getroot().find("BehaviorTree[@ID='FetchElement']")
    assert fetch is not None
    return text.replace("FETCH", ET.tostring(fetch, encoding="unicode"))


def _run(tmp_path: Path, conversion, text: str, name: str, *bb: str) -> tuple[dict, dict]:
    tree = tmp_path / f"{name}.xml"
    tree.write_text(_with_fetch(text, conversion.install_path))
    report, out = tmp_path / f"{name}.json", tmp_path / f"{name}_bb.json"
    main(["run", str(tree), "--world", str(conversion.world_path), "--seed", "0", "--quiet",
          "--report", str(report), "--bb-out", str(out), *(a for b in bb for a in ("--bb", b))])
    return json.loads(report.read_text()), json.loads(out.read_text())


@pytest.mark.slow
def test_place_and_fasten_succeed_and_fail_with_their_reasons(two_panels, tmp_path):
    conversion = two_panels[0]
    t = conversion.elements[0].target
    target = f"{t['x']};{t['y']};{t['z']};{t['yaw']}"
    off = f"{t['x'] + 0.05};{t['y']};{t['z']};{t['yaw']}"
    report, bb = _run(tmp_path, conversion, CHECKS, "checks", f"target={target}",
                      f"off_target={off}")
    assert report["status"] == "SUCCESS", report["reason"]
    (not_held,) = _reasons(report, "place_not_held")
    assert not_held == "the robot does not hold 'panel_w2' (attach it first)"
    (far,) = _reasons(report, "place_far")
    assert far.startswith("cannot place 'panel_w2' at 8.0000;5.0000;0.1500;0.0000: unreachable (")
    (tight,) = _reasons(report, "place_tight")
    # set down 2 mm above its target (the gap Place leaves), so 0.5 mm is out of tolerance
    assert tight.startswith("'panel_w2' is ") and "(tolerance 0.5 mm and 2 deg)" in tight
    assert 1.0 <= bb["dev_mm"] <= 20.0
    (off_reason,) = _reasons(report, "fasten_off")
    assert off_reason.startswith("'panel_w2' is ") and off_reason.endswith(
        "(tolerance 20 mm and 2 deg): not fastened")
    assert bb["to"] == "ground"
    (again,) = _reasons(report, "fasten_again")
    assert again == "'panel_w2' is already fastened to 'ground'"


@pytest.mark.slow
def test_place_fails_when_the_carried_panel_touched_something(two_panels, tmp_path):
    conversion = two_panels[0]
    t = conversion.elements[0].target
    target = f"target={t['x']};{t['y']};{t['z']};{t['yaw']}"
    # the push down is refused before the arm moves: the panel would meet the ground
    report, _ = _run(tmp_path, conversion, TOUCH.replace("CHECK", ""), "refused", target)
    (pushed,) = _reasons(report, "push_down")
    assert pushed.startswith("the tool's straight move would collide: ")
    assert "panel_w2 touches ground" in pushed
    # pushed down regardless (no checks), the panel touches the ground: Place refuses
    report, _ = _run(tmp_path, conversion,
                     TOUCH.replace("CHECK", 'check_collisions="false" joint_timeout="2"'),
                     "touch", target)
    assert report["status"] == "FAILURE"
    (reason,) = _reasons(report, "place_touched")
    assert reason == (
        "'panel_w2' touched 'ground' while carried, before the final placing motion"
    )


def test_payload_is_checked(tmp_path, capsys):
    b = three_rooms()
    ifc = b.write(tmp_path / "b.ifc")
    assert main(["bim", str(ifc), "--out", str(tmp_path / "o"), "--payload", "2.5"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 6
    lines = ifc.read_text().splitlines()
    panel = b.panels[0]
    line = next(i for i, text in enumerate(lines, 1) if text.startswith(f"#{panel.id()}="))
    assert err[0] == (
        f"{ifc}:{line}: #{panel.id()} IfcPlate 'Panel W1': 2.88 kg (MassDensity of 'Gypsum "
        "fibre board'), heavier than the 2.5 kg the robot can carry (--payload): not to be "
        "installed by it"
    )
    # the UR3's rated 3 kg takes them
    assert main(["bim", str(ifc), "--out", str(tmp_path / "o2")]) == 0


def test_the_stock_moves_as_one_per_seed(two_panels):
    from bt_manip.sim.world import World

    conversion = two_panels[0]
    poses = []
    for seed in (0, 1):
        with World(conversion.world_path, seed=seed) as world:
            poses.append({n: world.body_pose(n).xyz for n in ("panel_w2", "panel_w3",
                                                               "stand_panel_w2")})
    moved = [math.dist(poses[0][n][:2], poses[1][n][:2]) for n in poses[0]]
    assert max(moved) > 0.001
    # the distances between members stay the same
    for a, b in (("panel_w2", "panel_w3"), ("panel_w2", "stand_panel_w2")):
        assert math.dist(poses[0][a][:2], poses[0][b][:2]) == pytest.approx(
            math.dist(poses[1][a][:2], poses[1][b][:2]), abs=1e-6)


def test_office_panels_cross_the_door_straight(tmp_path):
    from bt_manip.sim.world_reader import parse_world

    ifc = three_rooms().write(tmp_path / "b.ifc")
    conversion = convert(BimOptions(ifc, tmp_path / "out"))
    root = ET.parse(conversion.install_path).getroot()
    calls = root.findall("BehaviorTree[@ID='Install']//SubTree")
    by_element = {c.get("element"): c for c in calls}
    for name in ("panel_w1", "panel_w2", "panel_w3"):
        assert by_element[name].get("ID") == "InstallElement"
    poses = parse_world(conversion.world_path).poses
    for name in ("panel_e1", "panel_e2", "panel_s1"):
        call = by_element[name]
        assert call.get("ID") == "InstallElementVia1Door"
        near, far = poses[call.get("door1_near")], poses[call.get("door1_far")]
        # from the workshop (west of the partition at x = 5) through the 1.6 m door at
        # y = 1.5, facing east all the way
        assert near.x < 5.0 < far.x
        assert near.y == pytest.approx(1.5, abs=1e-3) and far.y == pytest.approx(1.5, abs=1e-3)
        assert near.yaw == pytest.approx(0.0, abs=1e-3) and far.yaw == pytest.approx(0.0, abs=1e-3)
    via = root.find("BehaviorTree[@ID='InstallElementVia1Door']")
    assert via is not None
    ids = [n.get("ID") for n in via.iter("SubTree")]
    assert ids == ["FetchElement", "CarryThroughDoor", "PlaceElement"]
