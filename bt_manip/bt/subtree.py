"""``<SubTree ID="...">``: an instance of another tree, with its own blackboard.

Attributes of the SubTree element (other than ``ID``, ``name``, ``_autoremap`` and the
pre/post-condition scripts) remap the subtree's blackboard entries: ``port="{parent_key}"``
shares the parent's entry, ``port="{=}"`` shares the entry of the same name, a literal
``port="text"`` sets the subtree's entry to that text. With ``_autoremap="true"`` every key that
does not start with ``_`` is shared with the parent.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from bt_manip.bt.attributes import AttributeCheck, parse_condition_scripts
from bt_manip.bt.blackboard import Blackboard
from bt_manip.bt.node import BtNode, DecoratorNode
from bt_manip.bt.ports import Literal, Ref, convert_literal, format_literal, parse_reference
from bt_manip.bt.status import NodeStatus


class SubTree(DecoratorNode):
    """Ticks the root of the subtree and returns its status (reset once it finishes)."""

    NODE_ID = "SubTree"
    KIND = "SubTree"

    def __init__(self, tree_id: str, child: BtNode | None = None, name: str | None = None,
                 **attributes: Any) -> None:
        self.tree_id = tree_id
        super().__init__(name or tree_id, child, **attributes)

    @classmethod
    def check_attributes(cls, attributes: Mapping[str, Any]) -> AttributeCheck:
        check = AttributeCheck()
        parse_condition_scripts(attributes, check, "SubTree")
        for key, value in attributes.items():
            if key.startswith("_") and key != "_autoremap":  # a script, or not a port
                continue
            if key == "_autoremap":
                if isinstance(value, bool):
                    flag = value
                else:
                    try:
                        flag = convert_literal(str(value), bool)
                    except ValueError as e:
                        check.errors.append((f"bad value for _autoremap of SubTree: {e}", None))
                        continue
                check.bindings[key] = Literal(flag)
                check.texts[key] = format_literal(flag)
                continue
            if isinstance(value, (Ref, Literal)):
                check.bindings[key] = value
                check.texts[key] = ("{" + value.key + "}" if isinstance(value, Ref)
                                    else format_literal(value.value))
                continue
            text = value if isinstance(value, str) else format_literal(value)
            ref = parse_reference(text)
            if ref is not None:
                check.bindings[key] = Ref(key if ref in ("=", "") else ref)
            else:
                check.bindings[key] = Literal(value if not isinstance(value, str) else text)
            check.texts[key] = text
        return check

    @property
    def autoremap(self) -> bool:
        binding = self.bindings.get("_autoremap")
        return bool(binding.value) if isinstance(binding, Literal) else False

    def make_blackboard(self, parent: Blackboard) -> Blackboard:
        """The blackboard of this subtree instance, child of ``parent``."""
        remap = {k: b.key for k, b in self.bindings.items()
                 if isinstance(b, Ref) and k != "_autoremap"}
        bb = Blackboard(parent, remap=remap, autoremap=self.autoremap)
        for key, binding in self.bindings.items():
            if isinstance(binding, Literal) and key != "_autoremap":
                bb.set_own(key, binding.value)  # not remapped, even with _autoremap
        return bb

    def tick_node(self) -> NodeStatus:
        if self.bt_status is NodeStatus.IDLE:
            self.bt_status = NodeStatus.RUNNING
            self.status = NodeStatus.RUNNING.to_py_trees()
        status = self.child.execute_tick()
        if status.completed:
            self.reset_child()
        return status
