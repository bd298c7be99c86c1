"""The figures the documentation gives match the files they describe."""

from __future__ import annotations

import math
import re
from pathlib import Path

import pytest

from bt_manip.sim.world_reader import parse_world

ROOT = Path(__file__).resolve().parents[1]


def _section(readme: str, world: str) -> str:
    """The bullet of worlds/README.md describing ``world``, on one line."""
    match = re.search(rf"^- `{re.escape(world)}`:(.*?)(?=^- |\Z)", readme, re.S | re.M)
    assert match, world
    return " ".join(match.group(1).split())


def test_worlds_readme_describes_the_house_as_its_yaml_builds_it() -> None:
    text = _section((ROOT / "worlds" / "README.md").read_text(), "tb3_house.yaml")
    house = parse_world(ROOT / "worlds" / "tb3_house.yaml")
    widths = sorted(d.width for w in house.walls for d in w.doors)
    assert widths == [1.0, 1.0, 1.0, 1.0, 1.2, 1.2, 1.8]
    assert "seven doorways: one 1.8 m wide between workshop and living room" in text
    assert "six of 1.0-1.2 m" in text
    xs = [x for w in house.walls for x in (w.start[0], w.end[0])]
    ys = [y for w in house.walls for y in (w.start[1], w.end[1])]
    assert (max(xs) - min(xs), round(max(ys) - min(ys))) == (15.0, 10)
    assert "(15 m x 10 m" in text
    (panel,) = [o for o in house.objects if o.name == "panel"]
    assert [p.size for p in panel.parts] == [(1.2, 0.02, 0.15)] and panel.mass == 1.5
    assert "panel of 1.2 x 0.02 x 0.15 m (length x thickness x height, 1.5 kg)" in text
    (husky,) = house.robots
    assert husky.pose == (-1.0, 3.0, 0.0)
    assert (husky.randomize.x, husky.randomize.yaw) == ((-0.3, 0.3), (-0.5, 0.5))
    assert "corridor at (-1.0, 3.0), moved up to +-0.3 m and +-0.5 rad per seed" in text
    assert sorted(house.poses) == ["goal", "pregrasp_panel", "start"]
    assert "Named poses: `start`, `pregrasp_panel` and `goal`." in text


def test_worlds_readme_describes_the_table_as_its_yaml_builds_it() -> None:
    text = _section((ROOT / "worlds" / "README.md").read_text(), "sawyer_table.yaml")
    table = parse_world(ROOT / "worlds" / "sawyer_table.yaml")
    furniture = {f.name: f for f in table.furniture}
    cafe, bin_ = furniture["cafe_table"], furniture["bin"]
    assert cafe.pose.xyz[:2] == (1.0, 0.0)
    top = max(p.xyz[2] + p.size[2] / 2 for p in cafe.parts)
    assert math.isclose(top, 0.7475)
    assert "a cafe table at (1.0, 0, 0) with its top at z = 0.7475" in text
    assert bin_.pose.xyz == (0.75, -0.25, 0.8)
    outer = [max(p.xyz[i] + p.size[i] / 2 for p in bin_.parts)
             - min(p.xyz[i] - p.size[i] / 2 for p in bin_.parts) for i in range(3)]
    assert [round(v, 4) for v in outer] == [0.28, 0.28, 0.12]
    assert "bin at (0.75, -0.25, 0.8) (0.28 m square, 0.12 m high)" in text
    blocks = table.models
    assert len(blocks) == 10
    assert {b.parts[0].size for b in blocks} == {(0.05, 0.05, 0.05)}
    assert {b.mass for b in blocks} == {0.1}
    assert sorted({b.pose.xyz[0] for b in blocks}) == [0.7, 0.8]
    assert sorted({b.pose.xyz[1] for b in blocks}) == [0.0, 0.1, 0.2, 0.3, 0.4]
    assert {b.pose.xyz[2] for b in blocks} == {0.7725}
    assert {(b.randomize.x, b.randomize.yaw) for b in blocks} == {((-0.01, 0.01),
                                                                   (-0.1745, 0.1745))}
    assert ("ten 5 cm blocks of 0.1 kg on a 2 x 5 grid (x 0.7 and 0.8, y 0.0 to 0.4) at "
            "z = 0.7725 (jittered +-1 cm and +-10 deg per seed)") in text
    assert sorted(table.poses) == ["bin_drop"]


def test_sawyer_world_variants_change_only_what_their_headers_say() -> None:
    readme = (ROOT / "worlds" / "README.md").read_text()
    base = parse_world(ROOT / "worlds" / "sawyer_table.yaml")
    turned = parse_world(ROOT / "worlds" / "sawyer_table_yaw45.yaml")
    moved = parse_world(ROOT / "worlds" / "sawyer_table_bin_moved.yaml")
    quarter = (-0.7854, 0.7854)
    for variant in (turned, moved):
        assert [r.pose for r in variant.robots] == [r.pose for r in base.robots]
        assert [(m.name, m.parts, m.pose, m.mass) for m in variant.models] == [
            (m.name, m.parts, m.pose, m.mass) for m in base.models
        ]
        assert {(m.randomize.x, m.randomize.y, m.randomize.yaw) for m in variant.models} == {
            ((-0.01, 0.01), (-0.01, 0.01), quarter)
        }
        assert [f.parts for f in variant.furniture] == [f.parts for f in base.furniture]
    assert [f.pose for f in turned.furniture] == [f.pose for f in base.furniture]
    assert "+-45 deg" in _section(readme, "sawyer_table_yaw45.yaml")
    bin_ = {f.name: f for f in moved.furniture}["bin"]
    assert bin_.pose.xyz == (0.84, -0.27, 0.8)
    yaw = 2 * math.atan2(bin_.pose.quat[2], bin_.pose.quat[3])
    assert math.degrees(yaw) == pytest.approx(20.0, abs=0.01)
    text = _section(readme, "sawyer_table_bin_moved.yaml")
    assert "the bin moved to (0.84, -0.27)" in text and "turned by 20 deg" in text
    header = (ROOT / "worlds" / "sawyer_table_bin_moved.yaml").read_text()
    assert "(0.84, -0.27)" in header and "turned by 20 deg" in header
