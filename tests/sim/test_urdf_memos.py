"""URDFs read again in one process: what is remembered of them (whether a plain URDF names
meshes, the link and joint names a descriptor is checked against) follows every edit of the
URDF and of its meshes."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from bt_manip.errors import InputError
from bt_manip.sim.compose import composed_urdf
from bt_manip.sim.robot_description import _urdf_names

TRIANGLE = "v 0 0 0\nv 0.1 0 0\nv 0 0.1 0\nf 1 2 3\n"


def _urdf(mesh: str | None, link: str = "base", joint_upper: str = "1.5") -> str:
    geometry = (f'<mesh filename="{mesh}"/>' if mesh else '<box size="0.1 0.1 0.1"/>')
    return f"""<?xml version="1.0"?>
<robot name="probe">
  <link name="{link}"><collision><geometry>{geometry}</geometry></collision></link>
  <link name="tip"/>
  <joint name="j1" type="revolute"><parent link="{link}"/><child link="tip"/>
    <limit lower="-1.5" upper="{joint_upper}" effort="1" velocity="1"/></joint>
</robot>
"""


def test_a_plain_urdf_read_again_follows_its_meshes_and_its_bytes(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("BT_MANIP_CACHE", str(tmp_path / "cache"))
    mesh = tmp_path / "part.obj"
    mesh.write_text(TRIANGLE)
    urdf = tmp_path / "probe.urdf"
    urdf.write_text(_urdf("part.obj"))
    first = composed_urdf(urdf)
    assert first != urdf.resolve() and first.is_file()  # written with the mesh path resolved
    assert str(mesh.resolve()) in first.read_text()
    assert composed_urdf(urdf) == first
    mesh.unlink()  # the URDF's bytes are the same, its mesh is gone
    with pytest.raises(InputError) as err:
        composed_urdf(urdf)
    assert "mesh not found: part.obj" in str(err.value)
    mesh.write_text("not a mesh at all\n")
    with pytest.raises(InputError) as err:
        composed_urdf(urdf)
    assert "is not a Wavefront OBJ mesh" in str(err.value)
    mesh.write_text(TRIANGLE)
    assert composed_urdf(urdf) == first
    urdf.write_text(_urdf(None))  # no mesh any more: the URDF is loaded as it is
    assert composed_urdf(urdf) == urdf.resolve()


def test_the_names_a_descriptor_is_checked_against_follow_the_urdf(tmp_path: Path) -> None:
    urdf = tmp_path / "probe.urdf"
    urdf.write_text(_urdf(None))
    links, joints = _urdf_names(urdf)
    assert links == {"base", "tip"} and joints["j1"] == {
        "lower": "-1.5", "upper": "1.5", "effort": "1", "velocity": "1"}
    with pytest.raises(TypeError):
        joints["j1"]["upper"] = "9"  # type: ignore[index]  # read-only for every reader
    stat = urdf.stat()
    urdf.write_text(_urdf(None, link="chassis", joint_upper="2.5"))
    os.utime(urdf, ns=(stat.st_atime_ns, stat.st_mtime_ns))  # even with the old time stamp
    links, joints = _urdf_names(urdf)
    assert links == {"chassis", "tip"} and joints["j1"] is not None
    assert joints["j1"]["upper"] == "2.5"
