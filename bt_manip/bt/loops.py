"""BehaviorTree.CPP's LoopInt, LoopBool, LoopDouble and LoopString: run a child per queue item.

``<LoopInt queue="1;2;3" value="{i}">`` (or ``queue="{items}"``, a list on the blackboard)
takes the first item off the queue, writes it to ``value`` and ticks the child; one item per
tick:

- child SUCCESS (or SKIPPED): RUNNING; the next tick takes the next item;
- child RUNNING: RUNNING; the next tick ticks the child again with the same item;
- child FAILURE: FAILURE (the items left stay in the queue);
- queue empty, when no child is running: the status ``if_empty`` (SUCCESS by default).

A queue given as text is copied each time the node starts; a queue on the blackboard (a list)
is consumed in place, as BT.CPP pops its shared deque. An entry holding text, or no value, is
an error, as in BT.CPP 4.8.
"""

from __future__ import annotations

from types import GenericAlias
from typing import Any, ClassVar, cast

from py_trees.ports import PortInformation

from bt_manip.bt.node import BtNode, DecoratorNode, PortError
from bt_manip.bt.ports import InOutPortInformation, Literal, type_name
from bt_manip.bt.registry import registry
from bt_manip.bt.status import NodeStatus

IDLE = NodeStatus.IDLE
RUNNING = NodeStatus.RUNNING


class _Loop(DecoratorNode):
    ITEM: ClassVar[Any] = object

    def __init__(self, name: str | None = None, child: BtNode | None = None,
                 **attributes: Any) -> None:
        super().__init__(name, child, **attributes)
        self._child_running = False
        self._queue: list[Any] | None = None
        binding = self.bindings.get("queue")
        self._static = list(binding.value) if isinstance(binding, Literal) else None

    def _read_queue(self) -> list[Any] | None:
        binding = self.bindings.get("queue")
        if binding is None or isinstance(binding, Literal):
            return self._queue
        if not self.blackboard.has_value(binding.key):  # BT.CPP: "Any::cast failed ..."
            raise PortError(
                f"{self.describe()}: queue entry '{binding.key}' has no value; write a list "
                "into it first, or give the items in the queue port (queue=\"1;2;3\")")
        value = self.blackboard.get(binding.key)
        if value is None:
            return None
        if not isinstance(value, list):  # BT.CPP 4.8 does not convert text entries either
            raise PortError(
                f"{self.describe()}: queue entry '{binding.key}' holds a "
                f"{type(value).__name__}, not a list; write the items in the queue port "
                "(queue=\"1;2;3\") or store a list")
        return value

    def tick_node(self) -> NodeStatus:
        popped = False
        if self.bt_status is IDLE:
            self._child_running = False
            if self._static is not None:
                self._queue = list(self._static)
        if not self._child_running:
            queue = self._read_queue()
            if queue:
                value = queue.pop(0)
                popped = True
                self.set_output("value", value)
        if not popped and not self._child_running:
            return cast(NodeStatus, self.get_input("if_empty"))  # a NodeStatus port
        if self.bt_status is IDLE:
            self.set_running()
        status = self.child.execute_tick()
        self._child_running = status is RUNNING
        if status.completed:
            self.reset_child()
        if status is NodeStatus.FAILURE:
            return status
        return RUNNING


def _make_loop(node_id: str, item: type) -> type[_Loop]:
    cpp = type_name(item)
    ports = {
        "if_empty": PortInformation(
            NodeStatus, required=False, default_value=NodeStatus.SUCCESS,
            description="Status to return if queue is empty: SUCCESS, FAILURE, SKIPPED"),
        "queue": InOutPortInformation(
            GenericAlias(list, (item,)),  # list[item], made at run time
            description="items to loop over: a list entry, or text 'a;b;c'"),
    }
    cls = type(node_id, (_Loop,), {
        "NODE_ID": node_id,
        "ITEM": item,
        "INPUT_PORTS": ports,
        "OUTPUT_PORTS": {"value": PortInformation(item, description="the current item")},
        "PORT_TYPE_NAMES": {
            "queue": f"std::shared_ptr<std::deque<{cpp}, std::allocator<{cpp}> > >"},
        "__doc__": __doc__.split("\n\n")[1] if __doc__ else "",
        "__module__": __name__,
    })
    registry.register(cls, builtin=True)
    return cls


LoopInt = _make_loop("LoopInt", int)
LoopBool = _make_loop("LoopBool", bool)
LoopDouble = _make_loop("LoopDouble", float)
LoopString = _make_loop("LoopString", str)
