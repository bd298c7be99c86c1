"""world.yaml's text does not depend on which YAML emitter writes it.

The conversion writes with libyaml's emitter when every string of the world is printable ASCII
(plain or single-quoted, never folded in double quotes), else with PyYAML's: the text is the
same as ``yaml.safe_dump`` either way.
"""

from __future__ import annotations

import random
import string

import yaml

from bt_manip.bim.world_yaml import FAST_DUMPER as _FAST_DUMPER
from bt_manip.bim.world_yaml import plain_ascii as _plain_ascii
from bt_manip.bim.world_yaml import world_nodes, world_yaml


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
    (an anchor and an alias). world.yaml is the text of libyaml's emitter when every string
    is printable ASCII, else of PyYAML's."""
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
        assert text == _text(world, _FAST_DUMPER if _plain_ascii(world) else yaml.SafeDumper)
        kinds.add(_plain_ascii(world))
        if "again" in world:
            assert "&id001" in text and "*id001" in text
    assert kinds == {True, False}  # both emitters were used


def test_world_yaml_leaves_other_types_to_pyyaml() -> None:
    import pytest

    with pytest.raises(yaml.representer.RepresenterError):
        world_yaml({"value": object()})
    assert world_yaml({"pose": [1.0, 2.0]}) == "pose: [1.0, 2.0]\n"
