"""bt-manip registers every node BehaviorTree.CPP 4.8.2's factory registers by default, with the
same port names, directions, defaults and type names (so a TreeNodesModel exported by bt-manip
declares the built-ins as BT.CPP does)."""

from __future__ import annotations

from btcpp_reference import builtin_models

from bt_manip.bt import registry
from bt_manip.bt.models import spec_of


def ours() -> dict[str, dict[str, tuple[str, str | None, str | None]]]:
    models = {}
    for cls in registry.classes(builtin=True):
        spec = spec_of(cls)
        models[cls.NODE_ID] = {name: (p.direction, p.default, p.type_name)
                               for name, p in spec.ports.items()}
    # handled by the SubTree element itself
    models["SubTree"] = {"_autoremap": ("input", "false", "bool")}
    return models


def test_builtin_ids_ports_directions_defaults_and_types_match_btcpp() -> None:
    theirs = builtin_models()
    mine = ours()
    assert len(theirs) == 41
    assert sorted(mine) == sorted(theirs)
    for node_id, ports in theirs.items():
        assert mine[node_id] == ports, node_id
