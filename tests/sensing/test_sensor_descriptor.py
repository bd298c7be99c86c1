"""The ``sensors:`` section of a robot descriptor: read, defaulted, and refused with its line."""

from __future__ import annotations

from pathlib import Path

import pytest

from bt_manip.errors import InputError
from bt_manip.sim.robot_description import RobotDescription

HUSKY = Path("robots/husky_ur3.yaml")


def test_husky_declares_its_front_laser() -> None:
    (laser,) = RobotDescription.load("husky_ur3").sensors
    assert (laser.name, laser.link, laser.fov_deg, laser.beams) == (
        "front_laser", "top_plate_link", 270.0, 541)
    assert laser.angle_min == pytest.approx(-2.356194490192345)
    assert laser.angle_min + (laser.beams - 1) * laser.angle_increment == pytest.approx(
        2.356194490192345)


def _descriptor(tmp_path: Path, sensors: str) -> Path:
    (tmp_path / "parts").symlink_to((HUSKY.parent / "parts").resolve())
    text = HUSKY.read_text().split("sensors:")[0] + sensors
    path = tmp_path / "husky_laser.yaml"
    path.write_text(text)
    return path


def test_defaults_fill_what_is_left_out(tmp_path: Path) -> None:
    path = _descriptor(tmp_path, "sensors:\n  - {type: lidar2d, name: l, link: base_link}\n")
    (laser,) = RobotDescription.load(path).sensors
    assert (laser.fov_deg, laser.beams, laser.range_m, laser.noise_m, laser.rate_hz) == (
        270.0, 541, 12.0, 0.01, 10.0)
    assert laser.xyz == (0.0, 0.0, 0.0)


def test_bad_sensors_are_refused_with_their_lines(tmp_path: Path) -> None:
    path = _descriptor(tmp_path, (
        "sensors:\n"
        "  - {type: lidar2d, name: a, link: no_such_link}\n"
        "  - {type: sonar, name: b, link: base_link}\n"
        "  - {type: lidar2d, name: c, link: base_link, beams: 2.5, range_m: 500}\n"
        "  - {type: lidar2d, name: d, link: base_link, rpy: [0.5, 0, 0], colour: red}\n"
    ))
    first = len(path.read_text().split("sensors:")[0].splitlines()) + 1
    with pytest.raises(InputError) as err:
        RobotDescription.load(path)
    text = str(err.value)
    assert f"husky_laser.yaml:{first + 2}: sensors[1].type must be one of lidar2d" in text
    assert f"husky_laser.yaml:{first + 3}: sensors[2].beams must be a whole number" in text
    assert f"husky_laser.yaml:{first + 3}: sensors[2].range_m must be within" in text
    assert f"husky_laser.yaml:{first + 4}:" in text and "roll and pitch must be 0" in text
    assert "colour" in text
    other = tmp_path / "link"
    other.mkdir()
    path = _descriptor(other, "sensors:\n  - {type: lidar2d, name: a, link: no_such_link}\n")
    with pytest.raises(InputError, match="'no_such_link', which is not in the URDF"):
        RobotDescription.load(path)
