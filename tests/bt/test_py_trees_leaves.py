"""py_trees behaviours as bt-manip leaves, in XML and in Python trees."""

from __future__ import annotations

import random
from collections.abc import Iterator
from typing import Any, ClassVar

import py_trees
import pytest
from py_trees.common import Status
from py_trees.ports import BehaviourWithPorts, PortInformation

from bt_manip.bt import (
    Tree,
    TreeRuntimeError,
    from_py_trees,
    load_tree_string,
    registry,
    to_xml,
    validate,
)
from bt_manip.bt.context import TreeContext
from bt_manip.bt.controls import ReactiveSequence, Sequence
from bt_manip.bt.decorators import Inverter
from bt_manip.bt.leaves import AlwaysSuccess
from bt_manip.bt.pytrees.leaf import PyTreesLeaf, leaf_class_for, register_py_trees_behaviours
from bt_manip.bt.status import NodeStatus
from bt_manip.bt.xml_loader import load_tree
from bt_manip.clock import ManualClock
from bt_manip.errors import InputError

S, F, R = "SUCCESS", "FAILURE", "RUNNING"


@pytest.fixture(autouse=True)
def py_trees_nodes() -> None:
    register_py_trees_behaviours()


def xml(body: str) -> str:
    return f'<root BTCPP_format="4"><BehaviorTree ID="Main">{body}</BehaviorTree></root>'


def statuses(tree: Tree, ticks: int, clock: ManualClock | None = None) -> list[str]:
    out = []
    for _ in range(ticks):
        out.append(tree.tick().value)
        if clock is not None:
            clock.advance(0.25)
    return out


LEAVES = [
    ('<Success/>', {}, [S, S, S]),
    ('<Failure/>', {}, [F, F]),
    ('<Running/>', {}, [R, R]),
    ('<SuccessEveryN n="2"/>', {}, [F, S, F, S]),
    ('<Periodic n="1"/>', {}, [R, S, S, F, F, R]),
    ("<StatusQueue queue='[\"SUCCESS\", \"RUNNING\", \"FAILURE\"]' eventually=\"null\"/>", {},
     [S, R, F, S, R]),
    ("<StatusQueue queue='[\"SUCCESS\", \"RUNNING\"]' eventually=\"FAILURE\"/>", {},
     [S, R, F, F]),
    ('<TickCounter duration="2" completion_status="FAILURE"/>', {}, [R, R, F, R, R, F]),
    ('<Timer duration="0.5"/>', {}, [R, R, R, S, R]),
    ("<ProbabilisticBehaviour weights='[0, 0, 1]'/>", {}, [R, R]),
    ('<CheckBlackboardVariableExists variable_name="x"/>', {"x": 1}, [S]),
    ('<CheckBlackboardVariableExists variable_name="/x"/>', {}, [F]),
    ('<WaitForBlackboardVariable variable_name="x"/>', {}, [R, R]),
    ('<BlackboardToStatus variable_name="st"/>', {"st": Status.FAILURE}, [F]),
    ('<UnsetBlackboardVariable key="x"/>', {"x": 1}, [S]),
    ('<SetBlackboardVariable variable_name="y" variable_value="[1, 2]" overwrite="false"/>',
     {}, [S, F]),
]


@pytest.mark.parametrize(("body", "entries", "expected"), LEAVES)
def test_py_trees_leaves_in_xml(body: str, entries: dict[str, Any], expected: list[str]) -> None:
    clock = ManualClock()
    tree = load_tree_string(xml(body), context=TreeContext(clock=clock), blackboard=entries)
    assert statuses(tree, len(expected), clock) == expected


def test_leaves_write_and_remove_entries_of_the_tree() -> None:
    tree = load_tree_string(xml(
        '<Sequence><SetBlackboardVariable variable_name="/y" variable_value="3" overwrite="true"/>'
        '<UnsetBlackboardVariable key="x"/><WaitForBlackboardVariable variable_name="y"/>'
        '</Sequence>'), blackboard={"x": 1})
    assert tree.tick() is tree.bt_status
    assert tree.bt_status.value == S
    assert tree.blackboard.get("y") == 3
    assert not tree.blackboard.has_value("x")


def test_py_trees_leaves_in_python_trees() -> None:
    b = py_trees.behaviours
    every2 = b.SuccessEveryN("every2", 2)
    counter = b.TickCounter("counter", 1, Status.SUCCESS)
    queue = b.StatusQueue("queue", [Status.RUNNING, Status.SUCCESS], eventually=None)
    root = Sequence("root", children=[
        b.Success("ok"), Inverter("not", child=b.Failure("no")), every2, counter, queue,
        AlwaysSuccess(), b.Periodic("periodic", 5), b.Running("forever")])
    tree = Tree(root)
    got = []
    for _ in range(6):
        got.append(tree.tick().value)
    assert got == [F, R, R, R, R, R]  # every2 fails, counter and queue run, Periodic holds
    wrapped = root.children[2]
    assert isinstance(wrapped, PyTreesLeaf) and wrapped.behaviour is every2
    assert every2.count == 2
    assert counter.status == Status.SUCCESS and queue.status == Status.SUCCESS


def test_from_py_trees_keeps_the_objects_and_their_statuses() -> None:
    b = py_trees.behaviours
    leaf = b.TickCounter("count", 2, Status.SUCCESS)
    root = py_trees.composites.Selector("sel", memory=False, children=[b.Failure("f"), leaf])
    tree = from_py_trees(root)
    assert [tree.tick().value for _ in range(4)] == [R, R, S, R]
    assert leaf.status == Status.RUNNING and leaf.counter == 1


class Hello(py_trees.behaviour.Behaviour):
    """Says hello a few times, then succeeds."""

    log: ClassVar[list[str]] = []

    def __init__(self, name: str, greeting: str = "hello", times: int = 1) -> None:
        super().__init__(name)
        self.greeting = greeting
        self.times = times
        self.said = 0

    def setup(self, **kwargs: Any) -> None:
        self.log.append(f"setup {sorted(kwargs)}")

    def initialise(self) -> None:
        self.said = 0
        self.log.append("initialise")

    def update(self) -> Status:
        self.said += 1
        self.feedback_message = f"{self.greeting} #{self.said}"
        return Status.SUCCESS if self.said >= self.times else Status.RUNNING

    def terminate(self, new_status: Status) -> None:
        self.log.append(f"terminate {new_status.name}")


@pytest.fixture
def hello() -> Iterator[None]:
    assert registry.register(Hello) is Hello
    Hello.log.clear()
    yield
    registry.unregister("Hello")


def test_registered_behaviour_keeps_py_trees_contract(hello: None) -> None:
    tree = load_tree_string(xml(
        '<ReactiveSequence><ScriptCondition code="go"/>'
        '<Hello name="hi" greeting="bonjour" times="2"/></ReactiveSequence>'),
        blackboard={"go": True})
    node = tree.root.children[1]
    assert [tree.tick().value for _ in range(3)] == [R, S, R]
    assert node.feedback_message == "bonjour #1"
    assert Hello.log == ["initialise", "terminate SUCCESS", "initialise"]
    tree.blackboard.set("go", False)  # the condition fails: the RUNNING leaf is halted once
    assert tree.tick().value == F
    assert tree.tick().value == F
    assert Hello.log[-1] == "terminate INVALID" and Hello.log.count("terminate INVALID") == 1
    tree.blackboard.set("go", True)
    assert tree.tick().value == R
    assert Hello.log[-1] == "initialise"


def test_behaviour_tree_setup_reaches_wrapped_behaviours(hello: None) -> None:
    tree = load_tree_string(xml('<Sequence><Hello/><Hello name="two"/></Sequence>'))
    py_trees.trees.BehaviourTree(tree.root).setup(robot="r2")
    assert Hello.log == ["setup ['robot']", "setup ['robot']"]


@pytest.mark.parametrize(("body", "message"), [
    ('<SuccessEveryN n="two"/>',
     "<string>:1: bad value for parameter 'n' of SuccessEveryN: expected an integer, got 'two'"),
    ("<StatusQueue queue='[\"SUCCESS\", ' eventually=\"null\"/>",
     "<string>:1: bad value for parameter 'queue' of StatusQueue: expected JSON"),
    ("<StatusQueue queue='[\"DONE\"]' eventually=\"null\"/>",
     "<string>:1: bad value for parameter 'queue' of StatusQueue: expected one of SUCCESS, "
     "FAILURE, RUNNING, INVALID, got 'DONE'"),
    ('<SuccessEveryN n="{count}"/>',
     "<string>:1: parameter 'n' of SuccessEveryN is a constructor argument and cannot be a "
     "blackboard reference; give its value"),
    ('<TickCounter duration="1"/>',
     "<string>:1: TickCounter is missing its required port 'completion_status'"),
    ('<Success colour="red"/>', "<string>:1: 'colour' is not a port of Success"),
    ("<ProbabilisticBehaviour weights='[1, 2]'/>",
     "<string>:1: ProbabilisticBehaviour: ValueError: Either all or none of the probabilities "
     "must be specified"),
])
def test_bad_constructor_arguments_are_load_errors(body: str, message: str) -> None:
    with pytest.raises(InputError) as caught:
        load_tree_string(xml(body))
    assert str(caught.value).startswith(message), str(caught.value)


class Doubler(BehaviourWithPorts):
    """Doubles its input port into its output port."""

    INPUT_PORTS: ClassVar[dict[str, PortInformation]] = {
        "x": PortInformation(int, description="number")}
    OUTPUT_PORTS: ClassVar[dict[str, PortInformation]] = {
        "y": PortInformation(int, description="twice the number")}

    def update(self) -> Status:
        self._set_output("y", 2 * self.get_input("x"))
        return Status.SUCCESS


@pytest.fixture
def doubler() -> Iterator[None]:
    registry.register(Doubler)
    yield
    registry.unregister("Doubler")


def test_py_trees_ports_are_ports(doubler: None) -> None:
    tree = load_tree_string(xml(
        '<Sequence><Doubler x="{a}" y="{b}"/><Doubler x="21" y="{c}"/>'
        '<Doubler name="lost" x="{b}"/></Sequence>'), blackboard={"a": 5})
    assert tree.tick().value == S
    assert tree.blackboard.get("b") == 10 and tree.blackboard.get("c") == 42
    problems, _ = validate("t.xml", text=xml('<Doubler y="{b}"/>'))
    assert [p.message for p in problems] == [
        "Doubler is missing its required port 'x' (number); add x=\"...\""]
    model = to_xml(tree)
    assert '<input_port name="x" type="int">number</input_port>' in model
    assert '<output_port name="y" type="int">twice the number</output_port>' in model


class Keys(py_trees.behaviour.Behaviour):
    """Copies blackboard entry /source into target, through a py_trees client, and counts
    its runs in the root blackboard's entry 'runs'."""

    def __init__(self, name: str) -> None:
        super().__init__(name)
        self.client = self.attach_blackboard_client()
        self.client.register_key("/source", access=py_trees.common.Access.READ)
        self.client.register_key("target", access=py_trees.common.Access.WRITE)
        self.client.register_key("@runs", access=py_trees.common.Access.WRITE)

    def update(self) -> Status:
        self.client.target = self.client.get("/source") + 1
        runs = self.client.get("@runs") if self.client.exists("@runs") else 0
        self.client.set("@runs", runs + 1)
        return Status.SUCCESS


def test_blackboard_clients_use_the_blackboard_of_their_subtree() -> None:
    registry.register(Keys)
    try:
        tree = load_tree_string(
            '<root BTCPP_format="4" main_tree_to_execute="Main">'
            '<BehaviorTree ID="Main"><Sequence><Keys/>'
            '<SubTree ID="Inner" source="{target}" target="{out}"/></Sequence></BehaviorTree>'
            '<BehaviorTree ID="Inner"><Keys name="inner"/></BehaviorTree></root>',
            blackboard={"source": 1})
        assert tree.tick().value == S
    finally:
        registry.unregister("Keys")
    assert tree.blackboard.get("target") == 2  # /source and target are entries of Main
    assert tree.blackboard.get("out") == 3  # inside the SubTree they follow its remapping
    assert tree.blackboard.get("runs") == 2  # @runs is the root blackboard's entry
    assert "/target" not in py_trees.blackboard.Blackboard.storage


def test_random_leaf_reads_the_seeded_generator() -> None:
    tree = load_tree_string(xml("<ProbabilisticBehaviour/>"))
    random.seed(3)
    first = [tree.tick().value for _ in range(8)]
    random.seed(3)
    assert [tree.tick().value for _ in range(8)] == first


def test_to_xml_declares_py_trees_nodes_and_loads_back(tmp_path: Any) -> None:
    b = py_trees.behaviours
    d = py_trees.decorators

    def build() -> py_trees.behaviour.Behaviour:
        return py_trees.composites.Parallel(
            "par", py_trees.common.ParallelPolicy.SuccessOnOne(), children=[
                d.Repeat("rep", b.Success("s"), num_success=2),
                py_trees.composites.Sequence("seq", memory=False, children=[
                    b.TickCounter("tc", 3, Status.SUCCESS), b.Success("ok")]),
                d.FailureIsRunning("wait", b.SuccessEveryN("every2", 2)),
            ])

    original = from_py_trees(build())
    text = to_xml(original)
    assert '<PyTreesParallel name="par" policy="SuccessOnOne" synchronise="false">' in text
    assert '<SuccessEveryN name="every2" n="2"/>' in text
    assert '<TickCounter name="tc" duration="3" completion_status="SUCCESS"/>' in text
    assert '<Control ID="PyTreesParallel">' in text  # the TreeNodesModel for Groot2
    assert '<Action ID="TickCounter">' in text
    path = tmp_path / "tree.xml"
    path.write_text(text)
    reloaded = load_tree(str(path))
    expected = [original.tick().value for _ in range(6)]
    assert expected == [R, S, R, S, R, S]  # what py_trees itself gives
    assert [reloaded.tick().value for _ in range(6)] == expected
    assert ReactiveSequence.NODE_ID in text  # Sequence(memory=False) is BT.CPP's


def test_composites_and_decorators_cannot_be_registered_as_leaves() -> None:
    class Mine(py_trees.composites.Sequence):
        pass

    with pytest.raises(TypeError, match="Mine is a py_trees composite or decorator: only leaves"):
        registry.register(Mine)


class EveryOther(py_trees.decorators.Decorator):
    """A user's decorator: passes the child's status on odd ticks, RUNNING on even ones."""

    def __init__(self, name: str, child: py_trees.behaviour.Behaviour) -> None:
        super().__init__(name=name, child=child)
        self.ticks = 0

    def update(self) -> Status:
        self.ticks += 1
        return self.decorated.status if self.ticks % 2 else Status.RUNNING


class CountingSequence(py_trees.composites.Sequence):
    """A user's composite: a py_trees Sequence counting how often it starts."""

    def __init__(self, name: str, children: list[py_trees.behaviour.Behaviour]) -> None:
        super().__init__(name, memory=True, children=children)
        self.starts = 0

    def initialise(self) -> None:
        super().initialise()
        self.starts += 1


def test_users_own_composites_and_decorators_convert_and_tick_like_py_trees() -> None:
    def build() -> py_trees.behaviour.Behaviour:
        b = py_trees.behaviours
        return CountingSequence("seq", [
            EveryOther("other", b.SuccessEveryN("every2", 2)),
            py_trees.decorators.Repeat("rep", b.TickCounter("tc", 1, Status.SUCCESS), 2)])

    original = build()
    expected = []
    for _ in range(10):
        original.tick_once()
        expected.append(original.status.name)
    converted = build()
    tree = from_py_trees(converted)
    assert [tree.tick().value for _ in range(10)] == expected
    assert isinstance(tree.root, CountingSequence) and tree.root.starts == original.starts
    assert 'CountingSequence name="seq"' in to_xml(tree)


def test_eternal_guard_takes_a_script_in_xml() -> None:
    tree = load_tree_string(xml(
        '<PyTreesEternalGuard condition="battery > 20"><TickCounter duration="5" '
        'completion_status="SUCCESS"/></PyTreesEternalGuard>'), blackboard={"battery": 50})
    counter = tree.root.child.behaviour
    assert [tree.tick().value for _ in range(2)] == [R, R]
    tree.blackboard.set("battery", 10)
    assert tree.tick().value == F
    assert counter.status == Status.INVALID  # the guard stopped the RUNNING child
    with pytest.raises(InputError, match="script syntax error in condition"):
        load_tree_string(xml('<PyTreesEternalGuard condition="battery >"><Success/>'
                             '</PyTreesEternalGuard>'))


def test_an_exception_in_a_behaviour_is_a_tree_error_naming_the_node() -> None:
    tree = load_tree_string(xml('<BlackboardToStatus name="read" variable_name="missing"/>'))
    with pytest.raises(TreeRuntimeError) as caught:
        tree.tick()
    assert str(caught.value).startswith(
        "BlackboardToStatus 'read' (line 1): KeyError: \"client 'read' tried to access "
        "'/missing' but it does not yet exist on the blackboard\"")


class Success(py_trees.behaviour.Behaviour):
    """A user's class named like py_trees' ``Success``: fails."""

    def update(self) -> Status:
        return Status.FAILURE


def test_a_class_named_like_a_registered_one_converts_under_its_module_name() -> None:
    root = py_trees.composites.Sequence("seq", memory=True,
                                        children=[Success(name="one"), Success(name="two")])
    tree = from_py_trees(root)
    qualified = f"{__name__}.Success"
    assert [n.NODE_ID for n in tree.root.children] == [qualified, qualified]
    assert type(tree.root.children[0]) is type(tree.root.children[1])
    again = load_tree_string(to_xml(tree))
    assert again.tick() is NodeStatus.FAILURE
    assert registry.get("Success").BEHAVIOUR is py_trees.behaviours.Success


def test_to_xml_refuses_a_node_whose_id_is_registered_for_another_class() -> None:
    shadow = leaf_class_for(Success)  # ID "Success", not registered: py_trees' is
    tree = Tree(Sequence("seq", children=[shadow(name="one")]))
    with pytest.raises(ValueError, match=r"ID 'Success' is registered for "
                                         r"py_trees\.behaviours\.Success,"):
        to_xml(tree)
