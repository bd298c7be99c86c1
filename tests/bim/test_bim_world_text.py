"""world.yaml's text is ``yaml.dump``'s, whichever way it is written.

A world of dicts, lists, numbers, bools, None and printable ASCII strings is written directly
(:func:`~bt_manip.bim.world_yaml.direct_yaml`); any other goes through YAML nodes, written by
libyaml's emitter when every string of the world is printable ASCII (plain or single-quoted,
never folded in double quotes) and no key is empty or near 128 characters, else by PyYAML's:
the text is that of ``yaml.dump(world, Dumper=yaml.SafeDumper, sort_keys=False,
default_flow_style=None, width=100)`` every way.
"""

from __future__ import annotations

import math
import random
import string
from pathlib import Path
from typing import Any

import pytest
import yaml

from bt_manip.bim import convert as convert_module
from bt_manip.bim.world_yaml import FAST_DUMPER as _FAST_DUMPER
from bt_manip.bim.world_yaml import SIMPLE_KEY, direct_yaml, world_nodes, world_yaml
from bt_manip.bim.world_yaml import plain_ascii as _plain_ascii

SAMPLES = Path("../shared/samples/ifc")
SAMPLE_FILES = ["Example_Import_IFC.ifc", "modelo2016.ifc", "web-ifc-viewer_test.ifc"]


def _text(world: object, dumper: object) -> str:
    return yaml.dump(world, Dumper=dumper, sort_keys=False, default_flow_style=None, width=100)


def test_plain_ascii_worlds_read_the_same_from_both_emitters() -> None:
    rng = random.Random(7)
    alphabet = "".join(c for c in string.printable if c.isprintable())
    for _ in range(300):
        world = {
            "description": "".join(rng.choice(alphabet) for _ in range(rng.randint(0, 220))),
            "walls": [{"name": "".join(rng.choice(alphabet) for _ in range(rng.randint(0, 40))),
                       "xyz": [round(rng.uniform(-100, 100), 4), -0.0001, 1e-05]}],
        }
        assert _plain_ascii(world)
        assert _text(world, _FAST_DUMPER) == _text(world, yaml.SafeDumper)


def test_other_strings_go_to_pyyaml() -> None:
    assert not _plain_ascii({"description": "storey 'Térreo'"})
    assert not _plain_ascii({"walls": [{"name": "tab\there"}]})
    assert not _plain_ascii({"poses": {"line\nbreak": [0.0]}})
    assert _plain_ascii({"walls": [{"name": "wall_1", "xyz": [1.0, 2.0]}], "n": None})


def _random_value(rng: random.Random, depth: int) -> object:
    alphabet = string.printable + "éçñ→°"
    pick = rng.randrange(10 if depth < 4 else 6)
    if pick == 0:
        return rng.choice([0.0, -0.0, 1e17, -2.5e-07, float("inf"), float("-inf"), 1234.5678,
                           round(rng.uniform(-1e3, 1e3), 4)])
    if pick == 1:
        return rng.choice([True, False, None, 0, -7, 2**40])
    if pick in (2, 3, 4, 5):
        return "".join(rng.choice(alphabet) for _ in range(rng.choice([0, 3, 12, 130])))
    if pick in (6, 7):
        return [_random_value(rng, depth + 1) for _ in range(rng.randint(0, 5))]
    return {str(_random_value(rng, depth + 2)): _random_value(rng, depth + 1)
            for _ in range(rng.randint(0, 4))}


def test_world_yaml_is_pyyaml_dump() -> None:
    """The nodes built by bt-manip give PyYAML's text, written by either emitter: for scalars
    of every kind, non-ASCII and long strings, nested lists and dicts, and a list met twice
    (an anchor and an alias). world.yaml is the text of PyYAML's emitter, also where libyaml's
    differs (an empty key)."""
    rng = random.Random(11)
    kinds = set()
    for _ in range(400):
        world = {"name": _random_value(rng, 2), "walls": _random_value(rng, 0),
                 "poses": {"start": [rng.uniform(-5, 5), 0.0, 0.0]}}
        if rng.random() < 0.2:
            world["again"] = world["poses"]["start"]
        for dumper in (_FAST_DUMPER, yaml.SafeDumper):
            text = yaml.serialize(world_nodes(world), Dumper=dumper, width=100)
            assert text == _text(world, dumper)
        text = world_yaml(world)
        assert text == _text(world, yaml.SafeDumper)
        kinds.add(_plain_ascii(world))
        if "again" in world:
            assert "&id001" in text and "*id001" in text
    assert kinds == {True, False}  # both emitters were used


def test_world_yaml_leaves_other_types_to_pyyaml() -> None:
    import pytest

    with pytest.raises(yaml.representer.RepresenterError):
        world_yaml({"value": object()})
    assert world_yaml({"pose": [1.0, 2.0]}) == "pose: [1.0, 2.0]\n"


def _dump(data: object) -> str:
    """The oracle: PyYAML's own text."""
    return _text(data, yaml.SafeDumper)


def _converted_world(ifc: Path, out: Path, monkeypatch: pytest.MonkeyPatch) -> dict[str, Any]:
    """The world ``bt-manip bim`` builds from ``ifc`` (as handed to world_yaml), checked
    against the world.yaml written."""
    worlds: list[dict[str, Any]] = []

    def kept(world: dict[str, Any]) -> str:
        worlds.append(world)
        return world_yaml(world)

    monkeypatch.setattr(convert_module, "world_yaml", kept)
    convert_module.convert(convert_module.BimOptions(ifc, out))
    (world,) = worlds
    written = (out / "world.yaml").read_text()
    assert written.endswith(world_yaml(world))
    assert yaml.safe_load(written) == yaml.safe_load(_dump(world))
    return world


def _check_written_directly(world: dict[str, Any]) -> None:
    text = direct_yaml(world)
    assert text is not None, "a typical world is written directly, not through YAML nodes"
    assert text == world_yaml(world) == _dump(world)
    loaded = yaml.safe_load(text)  # the same world read back, written the same
    assert direct_yaml(loaded) == text


@pytest.mark.parametrize("name", SAMPLE_FILES)
def test_sample_worlds_are_written_directly_as_pyyaml_writes_them(
        name: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    pytest.importorskip("ifcopenshell")
    path = SAMPLES / name
    if not path.is_file():
        pytest.skip(f"{path} is absent (the shared samples are read relative to the project root)")
    _check_written_directly(_converted_world(path, tmp_path / "out", monkeypatch))


def test_generated_building_worlds_are_written_directly(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    pytest.importorskip("ifcopenshell")
    from ifc_buildings import real_features, three_rooms

    for i, building in enumerate([three_rooms(), real_features(three_rooms()),
                                  three_rooms(schema="IFC2X3")]):
        ifc = building.write(tmp_path / f"b{i}.ifc")
        world = _converted_world(ifc, tmp_path / f"out{i}", monkeypatch)
        assert world["walls"] and world["robots"]
        _check_written_directly(world)


TRICKY = [
    "yes", "No", "ON", "off", "~", "null", "Null", "true", "FALSE", "1e3", "1.5", "-1", "+1",
    "0x1F", "0o17", "0b101", "017", "1_000", "1:20", "2024-01-01", "2024-1-1 10:00:00", "=", "<<",
    ".inf",
    "-.inf", ".NaN", ".5", "-", "- a", "-a", "a: b", "a:b", "a:", ":a", ":", "?", "? a", "?a",
    "#x", "a#b", "a #b", "'q'", "a'b", '"q"', "[x]", "{y}", "x,y", "&a", "*a", "!t", "|", ">",
    "%p", "@x", "`x", "---", "--- a", "...", "..x", "--x", "", " ", "a ", " a", "a  b", "a - b",
    "_", "/path/to", "./x", "a.b-c_d", "x" * 300, " ".join(["word"] * 70), "it's 'quoted' " * 20,
    "  two  spaces  " * 10, "a " * 150, "é", "Térreo", "tab\there", "line\nbreak", "x\x7f",
]


def _string(rng: random.Random) -> str:
    pick = rng.random()
    if pick < 0.4:
        return rng.choice(TRICKY)
    if pick < 0.6:
        alphabet = string.printable if rng.random() < 0.3 else string.ascii_letters + " ':#-,"
        return "".join(rng.choice(alphabet) for _ in range(rng.choice([1, 3, 12, 60, 130, 250])))
    if pick < 0.63:
        return "".join(rng.choice("ab é→") for _ in range(rng.randint(0, 20)))
    return "".join(rng.choice(string.ascii_letters + "_0123456789")
                   for _ in range(rng.randint(1, 30)))


def _scalar(rng: random.Random) -> object:
    pick = rng.randrange(6)
    if pick == 0:
        return rng.choice([0.0, -0.0, 1e17, 1e16, -2.5e-07, 1e-05, math.inf, -math.inf, math.nan,
                           1e300, 5e-324, 123456789.123, rng.uniform(-1.0, 1.0),
                           round(rng.uniform(-1e3, 1e3), rng.randint(0, 6))])
    if pick == 1:
        return rng.choice([True, False, None])
    if pick == 2:
        return rng.choice([0, -7, 12, 2**40, 2**200, -(10**50)])
    return _string(rng)


def _key(rng: random.Random) -> str:
    if rng.random() < 0.3:
        return _string(rng)
    return rng.choice(["name", "xyz", "pose", "k", "a" * rng.randint(1, 110),
                       "k" * rng.randint(118, 130)])


def _structure(rng: random.Random, depth: int) -> object:
    pick = rng.randrange(10 if depth < 5 else 4)
    if pick < 4:
        return _scalar(rng)
    if pick < 6:  # flow style, short or wrapped
        return [_scalar(rng) for _ in range(rng.choice([0, 1, 3, 8, 30, 60]))]
    if pick < 8:
        return [_structure(rng, depth + 1) for _ in range(rng.randint(0, 4))]
    return {_key(rng): _structure(rng, depth + 1) for _ in range(rng.randint(0, 5))}


def test_direct_text_is_pyyaml_dump_on_random_structures() -> None:
    """Nested dicts and lists of every scalar (tricky, long, quoted, non-ASCII and empty
    strings, long keys, big and small floats, -0.0, nan, inf, huge ints), with long flow
    lists that wrap and long strings that fold: the direct text is PyYAML's whenever the
    writer takes the document, world_yaml's is always, and the writer takes most."""
    rng = random.Random(2024)
    direct = total = 0
    for _ in range(600):
        if rng.random() < 0.3:
            data = _structure(rng, 0)
        else:
            data = {"name": _string(rng), "walls": _structure(rng, 0), "more": _structure(rng, 1)}
        expected = _dump(data)
        text = direct_yaml(data)
        if type(data) not in (dict, list):
            assert text is None  # a scalar document is no world
            continue
        total += 1
        if text is not None:
            direct += 1
            assert text == expected
        assert world_yaml(data) == expected
    assert direct > total / 3


def _flow_cases() -> list[dict[str, Any]]:
    """Flow lists and dicts ending around column 100, after keys of every length, at every
    depth; strings folding around column 100, plain and quoted."""
    cases: list[dict[str, Any]] = []
    for width in range(1, 36):
        for key in ("k", "kk", "key" * 9, "k" * 60, "k" * 99, "k" * SIMPLE_KEY):
            floats = [1.25] * width
            cases.append({key: floats})
            cases.append({"a": [{key: floats, "b": {"c": [key, list(floats)]}}]})
            cases.append({key: {f"x{i}": 0.5 for i in range(width)}})
            cases.append({"a": [[key] * width, ["x" * width] * 3]})
            cases.append({key: "word " * width + "end", "q": "it's " * width})
            cases.append({key: [("w " * width).strip(), "it's " * width, "x"]})
            cases.append({key: {"w": ("w " * width).strip(), "it's": "'q' " * width}})
            cases.append({"l": [("w " * (width + 30)).strip(), ["x"], {key: "'" * width}]})
    return cases


def test_direct_text_wraps_and_folds_at_column_100_as_pyyaml() -> None:
    for case in _flow_cases():
        text = direct_yaml(case)
        assert text is not None
        assert text == _dump(case)


@pytest.mark.parametrize("value", TRICKY)
def test_tricky_strings_as_values_keys_and_flow_items(value: str) -> None:
    """Each string, written directly when printable ASCII (and, as a key, neither empty nor
    longer than a simple key), as PyYAML writes it: plain, or single-quoted."""
    as_values: list[Any] = [
        {"v": value}, {"v": [value]}, {"v": [value, 1.0]}, {"v": {"k": value}},
        {"l": [value, [value]]}, [value], [{"v": value}], [[value]],
        {"deep": [[{"x": [value, {"y": value}]}]]}, {"v": {"k": value, "l": [value]}},
    ]
    as_keys: list[Any] = [{value: 1}, {"m": {value: [1, [2]]}}, {"f": {value: 1, "g": value}},
                          [{value: {value: value}}]]
    printable = value.isascii() and value.isprintable()
    for cases, direct in ((as_values, printable),
                          (as_keys, printable and 0 < len(value) <= SIMPLE_KEY)):
        for case in cases:
            expected = _dump(case)
            assert world_yaml(case) == expected
            assert direct_yaml(case) == (expected if direct else None)


def test_the_direct_writer_leaves_other_documents_to_the_node_path() -> None:
    shared = [1.0, 2.0]
    others: list[Any] = [
        {"a": shared, "b": shared},  # an anchor and an alias
        {"a": [shared, shared]},
        {"pose": (1.0, 2.0)},  # a type the writer does not write
        {1: "int key"},
        {"k" * (SIMPLE_KEY + 1): 1},  # written after "? "
        {"": 1},
        {"name": "Térreo"},
        {"name": "tab\there"},
        "a scalar document",
        3.0,
    ]
    for data in others:
        assert direct_yaml(data) is None, data
    for data in others[:2] + others[3:8]:
        assert world_yaml(data) == _dump(data)
    assert "&id001" in world_yaml(others[0])
    longest = {"k" * SIMPLE_KEY: [1.0], "m": {"k" * SIMPLE_KEY: 1}}
    assert direct_yaml(longest) == _dump(longest)
    assert "?" not in _dump(longest)


def test_keys_libyaml_writes_otherwise_go_to_pyyaml() -> None:
    """libyaml's emitter writes an empty key, and keys of 121 to 128 characters, as simple keys
    where PyYAML's writes them after ``? ``: worlds holding one (and an anchor, so that they
    take the node path) are written by PyYAML's emitter."""
    shared = [0.0]
    for key in ["", *("k" * n for n in range(118, 132))]:
        for data in ({key: 1, "a": shared, "b": shared}, {"m": {key: [shared, shared]}},
                     {"s": {key, 1}, "m": {key: 1}}):
            assert world_yaml(data) == _dump(data)


def test_floats_ints_and_bools_as_pyyaml_writes_them() -> None:
    values: list[Any] = [0.0, -0.0, 1.0, -1.5708, 1e16, 1e17, -1e17, 1.5e300, 5e-324, 1e-05,
                         2.5e-07, math.inf, -math.inf, math.nan, 0.1 + 0.2, 123456789012345.67,
                         0, -0, 7, -7, 2**63, -(2**200), True, False, None]
    data = {"each": [{"v": v} for v in values], "flow": values,
            "map": {f"k{i}": v for i, v in enumerate(values)}}
    text = direct_yaml(data)
    assert text is not None
    assert text == _dump(data)
