"""Nav2's GoalUpdater decorator: a goal sent while the robot navigates replaces the goal.

Nav2's GoalUpdater listens on a topic (``goal_update``, and ``goals_update`` for a list of
goals). Here the root blackboard entries ``goal_update`` and ``goals_update`` are the topics:
each write to one (a script ``goal_update := '1;2;0'``, Python, another branch of the tree)
is a message. Messages carry no time stamps, so the order of writes stands in for Nav2's stamp
comparison: a received goal is used while it is newer than the input goal, i.e. until the
input goal itself is changed.
"""

from __future__ import annotations

from typing import Any

from py_trees.ports import PortInformation

from bt_manip.bt.node import BtNode, DecoratorNode
from bt_manip.bt.registry import registry
from bt_manip.bt.status import NodeStatus
from bt_manip.nav2.conditions import _plain

GOAL_TOPIC = "goal_update"
"""Nav2's default ``goal_updater_topic``: the blackboard entry read as the goal topic."""
GOALS_TOPIC = "goals_update"
"""Nav2's default ``goals_updater_topic``: the entry read as the goals topic."""


class _Topic:
    """One topic: the last message received (by its entry's write counter) and when, in
    writes seen by the decorator, it was received."""

    def __init__(self, key: str) -> None:
        self.key = key
        self.seen: int | None = None
        self.message: Any = None
        self.received_at = -1

    def poll(self, node: BtNode, clock: int) -> None:
        bb = node.blackboard
        key = "@" + self.key
        sequence = bb.sequence_id(key)
        if sequence is None or sequence == self.seen:
            return
        first_look = self.seen is None and sequence == 0
        self.seen = sequence
        if first_look:
            return
        try:
            value = bb.get(key)
        except KeyError:
            return
        if value is not None:
            self.message = value
            self.received_at = clock


class _Input:
    """An input port's value and when it last changed (in the decorator's clock)."""

    def __init__(self) -> None:
        self.value: Any = None
        self.changed_at = -1

    def read(self, value: Any, clock: int) -> Any:
        plain = _plain(value)
        if plain != self.value:
            self.value = plain
            self.changed_at = clock
        return value


@registry.register
class GoalUpdater(DecoratorNode):
    """Passes the goal on to its child, replaced by a newer one received on the goal topic.

    Each tick it reads ``input_goal`` (and ``input_goals``) and the topic entries (module
    docstring), writes ``output_goal`` (``output_goals``): the last goal received when it
    came after the input goal last changed, else the input goal; then ticks the child and
    returns its status (SUCCESS, FAILURE or RUNNING). Halted: the child is halted; the goals
    received are kept (as Nav2's subscription keeps its last message).
    """

    INPUT_PORTS: dict[str, PortInformation] = {
        "input_goal": PortInformation(object, False, "Original Goal"),
        "input_goals": PortInformation(object, False, "Original Goals"),
    }
    OUTPUT_PORTS: dict[str, PortInformation] = {
        "output_goal": PortInformation(object, False,
                                       "Received Goal by subscription if newer, else the "
                                       "original"),
        "output_goals": PortInformation(object, False,
                                        "Received Goals by subscription if newer, else the "
                                        "originals"),
    }

    def __init__(self, name: str | None = None, child: BtNode | None = None,
                 **attributes: Any) -> None:
        super().__init__(name, child, **attributes)
        self.goal_topic = _Topic(GOAL_TOPIC)
        self.goals_topic = _Topic(GOALS_TOPIC)
        self.goal_in = _Input()
        self.goals_in = _Input()
        self.clock = 0

    def _pass(self, port: str, out: str, given: _Input, topic: _Topic) -> None:
        value = given.read(self.get_input(port, None), self.clock)
        topic.poll(self, self.clock)
        newer = topic.message is not None and topic.received_at >= given.changed_at
        chosen = topic.message if newer else value
        if chosen is not None:
            self.set_output(out, chosen)

    def tick_node(self) -> NodeStatus:
        self.set_running()
        self.clock += 1
        self._pass("input_goal", "output_goal", self.goal_in, self.goal_topic)
        self._pass("input_goals", "output_goals", self.goals_in, self.goals_topic)
        return self.child.execute_tick()
