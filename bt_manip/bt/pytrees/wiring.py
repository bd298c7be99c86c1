"""The port wiring of a py_trees behaviour set up before conversion, as bt-manip bindings.

py_trees wires a behaviour's ports once, with ``setup_ports(port_remappings,
subtree_namespace)`` (called by the user's code or by py_trees' own XML parser): every port
is then registered in the behaviour's blackboard client, remapped to a py_trees key.
:func:`carried_wiring` reads that client back, port by port:

- a port remapped to a key (``/numbers/a``, or a relative key resolved in the namespace)
  becomes a reference to the entry of that key (``{numbers/a}``);
- a port left unremapped reads and writes the key py_trees made for it under the node
  (``/<namespace>/<name>_<uuid>/<port>``): a reference to that entry, so the converted tree
  keeps py_trees' blackboard as it is;
- an input given a constant (py_trees' parser turns ``port="2.5"`` into a key of the node
  holding the value) becomes that constant.

:func:`setup_entries` gives the entries py_trees' ``setup_ports()`` wrote for the behaviour
(the constants, the declared defaults of its outputs): a converted tree starts with them, as
py_trees' blackboard did.
"""

from __future__ import annotations

from typing import Any

import py_trees
from py_trees.ports import PortsMixin

from bt_manip.bt.ports import Binding, Literal, Ref
from bt_manip.bt.pytrees.storage import PORT_PREFIX


def _client(behaviour: Any) -> py_trees.blackboard.Client | None:
    client = vars(behaviour).get("_blackboard_client")
    return client if isinstance(client, py_trees.blackboard.Client) else None


def _targets(behaviour: PortsMixin) -> dict[str, str]:
    """Each wired port's py_trees key (absolute), as ``setup_ports()`` registered it."""
    client = _client(behaviour)
    if client is None:
        return {}
    remappings: dict[str, str] = object.__getattribute__(client, "remappings")
    targets = {}
    for port in (*behaviour.input_ports(), *behaviour.output_ports()):
        target = remappings.get(client.absolute_name(port))
        if target is not None and not target.startswith(PORT_PREFIX):  # not a leaf's own
            targets[port] = target
    return targets


def _storage() -> Any:
    return py_trees.blackboard.Blackboard.storage


def _constant_key(behaviour: PortsMixin, port: str) -> str:
    return behaviour._constant_storage_key(port)


def carried_wiring(behaviour: Any) -> dict[str, Binding]:
    """The bindings of ``behaviour``'s ports as its ``setup_ports()`` wired them (none when
    it was not set up)."""
    if not isinstance(behaviour, PortsMixin):
        return {}
    storage = _storage()
    bindings: dict[str, Binding] = {}
    for port, target in _targets(behaviour).items():
        constant = port in behaviour.input_ports() and target == _constant_key(behaviour, port)
        if constant and target in storage:
            bindings[port] = Literal(storage[target])
        else:  # (a constant no longer on py_trees' blackboard: its key, empty, as in py_trees)
            bindings[port] = Ref(target.lstrip("/"))
    return bindings


def subtree_namespace(behaviour: Any) -> str:
    """The namespace ``behaviour``'s ports were set up in ("/" when they were not)."""
    namespace = vars(behaviour).get("_subtree_namespace")
    return namespace if isinstance(namespace, str) else "/"


def setup_entries(behaviour: Any) -> dict[str, Any]:
    """The entries (bt-manip names) that ``setup_ports()`` wrote for ``behaviour`` and that
    py_trees' blackboard still holds: its constants and its outputs' declared defaults."""
    if not isinstance(behaviour, PortsMixin):
        return {}
    storage = _storage()
    written = {}
    for port, target in _targets(behaviour).items():
        constant = port in behaviour.input_ports() and target == _constant_key(behaviour, port)
        seeded = port in behaviour.output_ports() and \
            behaviour.output_ports()[port].has_default
        if (constant or seeded) and target in storage:
            written[target.lstrip("/")] = storage[target]
    return written


def forget_client(behaviour: Any) -> None:
    """Drop the blackboard client of ``behaviour``'s earlier ``setup_ports()`` from its
    clients (it is wired again; the new client replaces it)."""
    client = _client(behaviour)
    if client is not None:
        clients = behaviour.blackboards
        clients[:] = [c for c in clients if c is not client]
