"""world.yaml's text does not depend on which YAML emitter writes it.

The conversion writes with libyaml's emitter when every string of the world is printable ASCII
(plain or single-quoted, never folded in double quotes), else with PyYAML's: the text is the
same as ``yaml.safe_dump`` either way.
"""

from __future__ import annotations

import random
import string

import yaml

from bt_manip.bim.convert import _FAST_DUMPER, _plain_ascii


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
