"""A malformed line of an IFC file is reported at its line; placement matrices read anywhere."""

from __future__ import annotations

import sys

import numpy as np
import pytest

pytest.importorskip("ifcopenshell")

import ifcopenshell
import ifcopenshell.util.placement as placement
from ifc_buildings import three_rooms

from bt_manip.bim.parse_log import _entries
from bt_manip.bim.shapes import ShapeReader, _operator_matrix
from bt_manip.cli import main


def _break_line(path, number: int, old: bytes, new: bytes) -> None:
    lines = path.read_bytes().split(b"\n")
    assert old in lines[number - 1]
    lines[number - 1] = lines[number - 1].replace(old, new, 1)
    path.write_bytes(b"\n".join(lines))


def _entity_lines(path) -> list[int]:
    return [i for i, text in enumerate(path.read_bytes().split(b"\n"), start=1)
            if text.startswith(b"#")]


@pytest.mark.parametrize("damage", ["class", "token"])
def test_a_broken_line_is_reported_at_its_line(tmp_path, capsys, damage):
    path = three_rooms().write(tmp_path / "three.ifc")
    number = _entity_lines(path)[-2]  # near the end of the file
    if damage == "class":  # a misspelt class name: the entity would be dropped
        _break_line(path, number, b"=", b"=XX")
    else:  # a stray character in its attributes
        _break_line(path, number, b"(", b"(@", )
    out = tmp_path / "out"
    code = main(["bim", str(path), "--out", str(out)])
    err = capsys.readouterr().err
    assert code == 2
    assert "Traceback" not in err
    first = err.strip().splitlines()[0]
    assert first.startswith(f"{path}:{number}:")
    assert "the IFC file cannot be parsed here: " in first
    assert ("XX" if damage == "class" else "@") in first
    assert not (out / "world.yaml").exists()


def test_a_broken_line_after_bytes_that_are_not_utf8_is_reported_at_its_line(tmp_path,
                                                                               capsys):
    # the parser reads the text with each invalid byte replaced (three bytes in UTF-8), so
    # its offsets are counted in that text, not in the file's bytes
    path = three_rooms().write(tmp_path / "three.ifc")
    number = _entity_lines(path)[-2]
    lines = path.read_bytes().split(b"\n")
    named = max(i for i in range(number - 1) if b"'" in lines[i])  # a line with a string
    quote = lines[named].index(b"'")
    lines[named] = lines[named][:quote + 1] + b"\xff" * 40 + lines[named][quote + 1:]
    path.write_bytes(b"\n".join(lines))
    _break_line(path, number, b"=", b"=XX")
    code = main(["bim", str(path), "--out", str(tmp_path / "out")])
    first = capsys.readouterr().err.strip().splitlines()[0]
    assert code == 2
    assert first.startswith(f"{path}:{number}:")
    assert "XX" in first


def test_the_sound_file_converts(tmp_path, capsys):
    path = three_rooms().write(tmp_path / "three.ifc")
    assert main(["bim", str(path), "--out", str(tmp_path / "out")]) == 0
    capsys.readouterr()
    assert (tmp_path / "out" / "world.yaml").is_file()


def test_log_lines_of_both_formats() -> None:
    log = ("[error] [2026-01-01 10:00:00] token x9 at offset 12 invalid instance name\n"
           "[warning] [VAL016] [2026-01-01 10:00:00] Expected 4 attribute values, found 7\n"
           '{"level":"error","message":"Unexpected \'","time":"2026-01-01 10:00:00"}\n')
    assert _entries(log) == [("error", "token x9 at offset 12 invalid instance name"),
                             ("warning", "Expected 4 attribute values, found 7"),
                             ("error", "Unexpected '")]


def test_2d_placement_matrix_under_a_profiler() -> None:
    # ifcopenshell resizes the direction array of a 2D placement in place, which numpy
    # refuses while a profiler holds a reference to it; the reader computes it itself
    f = ifcopenshell.file(schema="IFC4")
    axis = f.createIfcAxis2Placement2D(f.createIfcCartesianPoint((1.0, 2.0)),
                                       f.createIfcDirection((0.6, 0.8)))
    calls: list[str] = []
    sys.setprofile(lambda frame, event, arg: calls.append(event))
    try:
        m = ShapeReader(1.0).axis(axis)
    finally:
        sys.setprofile(None)
    assert calls
    expected = np.array([[0.6, -0.8, 0.0, 1.0], [0.8, 0.6, 0.0, 2.0], [0.0, 0.0, 1.0, 0.0],
                         [0.0, 0.0, 0.0, 1.0]])
    assert np.allclose(m, expected, atol=1e-12)
    assert np.allclose(m, placement.get_axis2placement(axis), atol=1e-12)


def test_transformation_operator_as_ifcopenshell_reads_it() -> None:
    f = ifcopenshell.file(schema="IFC4")
    point = f.createIfcCartesianPoint((1.0, 2.0, 3.0))
    mirrored = f.createIfcCartesianTransformationOperator3D(
        f.createIfcDirection((0.0, 1.0, 0.0)), f.createIfcDirection((1.0, 0.0, 0.0)), point,
        2.0, f.createIfcDirection((0.0, 0.0, 1.0)))
    stretched = f.createIfcCartesianTransformationOperator3DnonUniform(
        None, None, point, 1.5, None, 2.0, None)
    for operator in (mirrored, stretched):
        ours = _operator_matrix(operator)
        assert np.allclose(ours, placement.get_cartesiantransformationoperator3d(operator),
                           atol=1e-12)
    # x along y, y mirrored onto x, scale 2
    assert np.allclose(_operator_matrix(mirrored)[:3, :3],
                       [[0.0, 2.0, 0.0], [2.0, 0.0, 0.0], [0.0, 0.0, 2.0]], atol=1e-12)
    assert np.allclose(np.diag(_operator_matrix(stretched))[:3], [1.5, 2.0, 1.5], atol=1e-12)
