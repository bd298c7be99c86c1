"""A seeded generator of random BT.CPP v4 trees over the built-in nodes, with their schedules.

``generate(seed)`` always gives the same case for the same seed. A case is a main tree of
depth 2 to 5 (its root is a control or a decorator), up to two subtree definitions reached
through ``<SubTree>`` with explicit port remapping or ``_autoremap``, a starting blackboard and
a schedule of 3 to 8 ``tickOnce`` calls (some of them ``tickExactlyOnce`` in a fifth of the
cases) with, in some cases, a ``haltTree`` between them or at the end.

Nodes: every built-in that BehaviorTree.CPP 4.8.2's factory registers (controls, decorators,
Script/ScriptCondition, SetBlackboard/UnsetBlackboard, Sleep, WasEntryUpdated, the Loop*
nodes, SkipUnlessUpdated, WaitValueUpdate, SubTree), the pre/post-condition attributes
(``_skipIf``, ``_failureIf``, ``_successIf``, ``_while``, ``_onSuccess``, ``_onFailure``,
``_onHalted``, ``_post``) and the stateful test leaf of :mod:`differential.leaf`.

Limits that keep a run comparable (not exclusions of behaviour, see also
:mod:`differential.rules`):

- durations are 0 ms only: BT.CPP's Sleep, Delay and Timeout run on wall-clock timer threads;
- ``Repeat``/``RetryUntilSuccessful`` get 1 to 3 cycles (a literal, or the entry ``k0`` that no
  node writes), never -1, since a child that always finishes at once would loop forever inside
  one ``tickOnce`` (in both engines);
- scripts never chain ``-`` or ``/`` (BT.CPP 4.8.2 groups them from the right) and use no
  operator that BT.CPP's grammar lacks.

``enabled`` restricts the node IDs generated (used while built-ins are still missing from
bt-manip, see :func:`differential.rules.enabled_builtins`).
"""

from __future__ import annotations

import random
from collections.abc import Callable, Collection

from differential.leaf import LEAF_ID, leaf_name
from differential.spec import HALT, TICK, TICK_EXACTLY_ONCE, Case, Node

INT_VARS = ("c0", "c1", "c2")
BOOL_VARS = ("b0", "b1")
STR_VARS = ("s0",)
POOL = INT_VARS + BOOL_VARS + STR_VARS
NEW_NUMBERS = ("n0", "n1")
NEW_TEXTS = ("t0",)

SEQUENCES = ("Sequence", "SequenceWithMemory", "ReactiveSequence", "Fallback", "ReactiveFallback",
             "AsyncSequence", "AsyncFallback")
CONTROLS = (*SEQUENCES, "Parallel", "ParallelAll", "IfThenElse", "WhileDoElse",
            "Switch2", "Switch3", "Switch4", "Switch5", "Switch6")
DECORATORS = ("Inverter", "ForceSuccess", "ForceFailure", "KeepRunningUntilFailure", "Repeat",
              "RetryUntilSuccessful", "Timeout", "Delay", "RunOnce", "Precondition",
              "LoopInt", "LoopBool", "LoopDouble", "LoopString", "SkipUnlessUpdated",
              "WaitValueUpdate")
LEAVES = ("AlwaysSuccess", "AlwaysFailure", "Script", "ScriptCondition", "SetBlackboard",
          "UnsetBlackboard", "Sleep", "WasEntryUpdated")
BUILTINS = (*CONTROLS, *DECORATORS, *LEAVES)
# Nodes that emit the wake-up signal (tickOnce re-ticks the root at once), and parents that
# halt a RUNNING child when it is re-ticked. Two emitters under one such parent can halt each
# other forever within a single tickOnce (in both engines), so the generator never puts two
# there (one is fine: it makes progress at each re-tick).
EMITTERS = ("Repeat", "RetryUntilSuccessful", "SequenceWithMemory", "AsyncSequence",
            "AsyncFallback", "Delay")
HALTERS = ("ReactiveSequence", "ReactiveFallback", "WhileDoElse", "Switch2", "Switch3",
           "Switch4", "Switch5", "Switch6")
STATUS_TEXTS = ("SUCCESS", "FAILURE", "RUNNING", "SKIPPED")
PRE_ATTRIBUTES = ("_skipIf", "_failureIf", "_successIf", "_while")
POST_ATTRIBUTES = ("_onSuccess", "_onFailure", "_onHalted", "_post")


class Generator:
    """Random cases from one seed; see the module docstring."""

    def __init__(self, seed: int, enabled: Collection[str] | None = None) -> None:
        self.rng = random.Random(seed)
        self.seed = seed
        self.enabled = set(BUILTINS if enabled is None else enabled)
        self.subtrees: dict[str, Node] = {}
        self.leaf_count = 0
        self.in_subtree = False
        self.halting_depth = 0  # how many HALTERS are above the node being generated
        self.emitters = 0  # EMITTERS generated under the outermost of them

    # ------------------------------------------------------------------ scripts

    def int_var(self) -> str:
        return self.rng.choice(INT_VARS)

    def condition(self, depth: int = 0, pure: bool = False) -> str:
        """A script whose value is a bool; unless ``pure``, it may first increment a counter."""
        r = self.rng.random()
        c, k = self.int_var(), self.rng.randint(0, 3)
        if r < 0.35:
            op = self.rng.choice((">", ">=", "<", "<=", "==", "!="))
            return f"{c} {op} {k}"
        if r < 0.55:
            b = self.rng.choice(BOOL_VARS)
            return b if self.rng.random() < 0.5 else f"!{b}"
        if r < 0.62:
            return self.rng.choice(("s0 == 'a'", "s0 != 'b'"))
        if r < 0.68:
            return self.rng.choice(("true", "false"))
        if r < 0.80 and depth == 0:
            op = self.rng.choice(("&&", "||"))
            return f"{self.condition(1, True)} {op} {self.condition(1, True)}"
        if r < 0.92 and not pure:
            return f"{c} += 1; {c} > {k + 1}"
        return f"{c} < {self.int_var()}"

    def action(self, depth: int = 0) -> str:
        r = self.rng.random()
        c = self.int_var()
        if r < 0.30:
            return f"{c} += 1"
        if r < 0.38:
            return f"{c} -= 1"
        if r < 0.46:
            return f"{c} := {self.rng.randint(0, 3)}"
        if r < 0.52:
            return f"{c} := {self.int_var()} + {self.rng.randint(1, 2)}"
        if r < 0.62:
            b = self.rng.choice(BOOL_VARS)
            return f"{b} = !{b}"
        if r < 0.67:
            return f"{self.rng.choice(BOOL_VARS)} := {self.condition(1, True)}"
        if r < 0.72:
            return self.rng.choice(("s0 := 'a'", "s0 := 'b'", "s0 := s0 .. 'x'"))
        if r < 0.80:
            n = self.rng.choice(NEW_NUMBERS)
            return self.rng.choice((f"{n} := {c} * 2", f"{n} := 2.5", f"{n} := {c} / 2",
                                    f"{n} := {c} > 1 ? 5 : 6"))
        if r < 0.83:
            return self.rng.choice(("t0 := 'q'", "t0 := s0 .. 'y'"))
        if r < 0.86:  # errors in BT.CPP: arithmetic on text, a type change of an entry
            return self.rng.choice(("s0 += 1", "n0 += 1", "s0 := 5", "c0 := 'x'",
                                    "c1 := '4'", "b0 := 2"))
        if depth == 0:
            return f"{self.action(1)}; {self.action(1)}"
        return f"{c} += 1"

    # ------------------------------------------------------------------ nodes

    def pick(self, choices: tuple[str, ...], weights: tuple[float, ...]) -> str:
        blocked = EMITTERS if self.halting_depth and self.emitters else ()
        names = [c for c in choices if c in self.enabled and c not in blocked]
        ws = [w for c, w in zip(choices, weights, strict=True)
              if c in self.enabled and c not in blocked]
        tag = self.rng.choices(names, ws)[0]
        if self.halting_depth and tag in EMITTERS:
            self.emitters += 1
        return tag

    def node(self, depth: int, max_depth: int) -> Node:
        """A node at ``depth`` (1 is the root) in a tree of at most ``max_depth`` levels."""
        r = self.rng.random()
        if depth == 1 or (depth < max_depth and r < 0.55):
            kind_roll = self.rng.random()
            node = self.control(depth, max_depth) if kind_roll < 0.6 else self.decorator(
                depth, max_depth)
        else:
            node = self.leaf()
        self.decorate(node)
        return node

    def children(self, count: int, depth: int, max_depth: int) -> list[Node]:
        return [self.node(depth + 1, max_depth) for _ in range(count)]

    def control(self, depth: int, max_depth: int) -> Node:
        weights = (6, 5, 6, 6, 5, 3, 3, 4, 3, 5, 5, 2, 1, 1, 1, 1)
        tag = self.pick(CONTROLS, weights)
        halter = tag in HALTERS
        self.halting_depth += halter
        try:
            return self._control(tag, depth, max_depth)
        finally:
            self.halting_depth -= halter
            if not self.halting_depth:
                self.emitters = 0

    def _control(self, tag: str, depth: int, max_depth: int) -> Node:
        rng = self.rng
        if tag in SEQUENCES:
            return Node(tag, {}, self.children(rng.randint(1, 4), depth, max_depth))
        if tag == "Parallel":
            kids = self.children(rng.randint(1, 4), depth, max_depth)
            n = len(kids)
            attrs = {}
            if rng.random() < 0.7:
                attrs["success_count"] = str(rng.choice((-1, 1, n, min(2, n))))
            if rng.random() < 0.6:
                attrs["failure_count"] = str(rng.choice((-1, 1, n, min(2, n))))
            return Node(tag, attrs, kids)
        if tag == "ParallelAll":
            kids = self.children(rng.randint(1, 4), depth, max_depth)
            attrs = {}
            if rng.random() < 0.6:
                attrs["max_failures"] = str(rng.choice((-1, 1, len(kids))))
            return Node(tag, attrs, kids)
        if tag in ("IfThenElse", "WhileDoElse"):
            return Node(tag, {}, self.children(rng.randint(2, 3), depth, max_depth))
        cases = int(tag[-1])
        attrs = {"variable": "{s0}" if rng.random() < 0.95 else rng.choice(("{c0}", "{t0}"))}
        values = ["a", "b", "ax", "1", "c"]
        rng.shuffle(values)
        for i in range(cases):
            attrs[f"case_{i + 1}"] = values[i % len(values)]
        return Node(tag, attrs, self.children(cases + 1, depth, max_depth))

    def decorator(self, depth: int, max_depth: int) -> Node:
        weights = (5, 3, 3, 2, 4, 4, 2, 2, 3, 4, 1.5, 1, 1, 1.5, 2, 1.5)
        tag = self.pick(DECORATORS, weights)
        rng = self.rng
        attrs: dict[str, str] = {}
        if tag == "Repeat":
            attrs["num_cycles"] = self.count_port()
        elif tag == "RetryUntilSuccessful":
            attrs["num_attempts"] = self.count_port()
        elif tag == "Timeout":
            attrs["msec"] = "0"
        elif tag == "Delay":
            attrs["delay_msec"] = "0"
        elif tag == "RunOnce":
            if rng.random() < 0.6:
                attrs["then_skip"] = rng.choice(("true", "false", "{b0}"))
        elif tag == "Precondition":
            attrs["if"] = self.condition()
            if rng.random() < 0.7:
                attrs["else"] = rng.choice(STATUS_TEXTS)
        elif tag.startswith("Loop"):
            queue, key = {
                "LoopInt": (("1;2;3", "4", "2;5"), "li"),
                "LoopBool": (("true;false", "false", "true;true;false"), "lb"),
                "LoopDouble": (("1.5;2", "0.5", "1;2.5;3"), "ld"),
                "LoopString": (("a;b", "x", "p;q;r"), "ls"),
            }[tag]
            attrs["queue"] = rng.choice(queue)
            attrs["value"] = "{" + key + "}"
            if rng.random() < 0.5:
                attrs["if_empty"] = rng.choice(STATUS_TEXTS)
        elif tag in ("SkipUnlessUpdated", "WaitValueUpdate"):
            attrs["entry"] = self.entry_ref()
        return Node(tag, attrs, self.children(1, depth, max_depth))

    def count_port(self) -> str:
        """A cycle count: a literal 1-3, or a reference to ``k0`` (1-3, never written)."""
        return "{k0}" if self.rng.random() < 0.2 else str(self.rng.randint(1, 3))

    def entry_ref(self) -> str:
        key = self.rng.choice(POOL)
        return "{" + key + "}" if self.rng.random() < 0.5 else key

    def leaf(self) -> Node:
        if not self.in_subtree and self.rng.random() < 0.08:
            return self.subtree_call()
        weights = (10, 8, 14, 12, 4, 2, 3, 3)
        roll = self.rng.random()
        if roll < 0.38:
            return self.test_leaf()
        tag = self.pick(LEAVES, weights)
        rng = self.rng
        if tag == "Script":
            return Node(tag, {"code": self.action()})
        if tag == "ScriptCondition":
            return Node(tag, {"code": self.condition()})
        if tag == "SetBlackboard":
            key = rng.choice((*POOL, *NEW_NUMBERS, *NEW_TEXTS))
            if rng.random() < 0.05:  # the entry named by the value of s0
                key = "{s0}"
            value = rng.choice(("1", "7", "abc", "true", "2.5", "{c0}", "{s0}", "{b1}"))
            return Node(tag, {"value": value, "output_key": key})
        if tag == "UnsetBlackboard":
            return Node(tag, {"key": rng.choice((*POOL, *NEW_NUMBERS))})
        if tag == "Sleep":
            return Node(tag, {"msec": "0"})
        if tag == "WasEntryUpdated":
            return Node(tag, {"entry": self.entry_ref()})
        return Node(tag)

    def test_leaf(self) -> Node:
        self.leaf_count += 1
        length = self.rng.choice((1, 1, 2, 3, 3, 4))
        pattern = "".join(self.rng.choice("SFRRR" if i < length - 1 else "SFSFR")
                          for i in range(length))
        return Node(LEAF_ID, {"name": leaf_name(self.leaf_count, pattern)})

    def subtree_call(self) -> Node:
        rng = self.rng
        if not self.subtrees or (len(self.subtrees) < 2 and rng.random() < 0.5):
            tree_id = f"Sub{len(self.subtrees) + 1}"
            self.in_subtree = True
            self.subtrees[tree_id] = self.node(1, rng.randint(2, 3))
            self.in_subtree = False
        else:
            tree_id = rng.choice(sorted(self.subtrees))
            inside = sum(n.tag in EMITTERS for n in self.subtrees[tree_id].walk())
            if self.halting_depth and inside + self.emitters > 1:
                return self.test_leaf()
            if self.halting_depth:
                self.emitters += inside
        attrs = {"ID": tree_id}
        if rng.random() < 0.5:
            attrs["_autoremap"] = "true"
        else:
            for key in POOL:
                roll = rng.random()
                if roll < 0.45:
                    attrs[key] = "{" + key + "}"
                elif roll < 0.55:
                    attrs[key] = "{=}"
                elif roll < 0.7:
                    others = [k for k in POOL if k[0] == key[0]]
                    attrs[key] = "{" + rng.choice(others) + "}"
                elif roll < 0.75:
                    attrs[key] = rng.choice(("1", "a"))
        return Node("SubTree", attrs)

    def decorate(self, node: Node) -> None:
        """Add pre/post-condition attributes to some nodes."""
        rng = self.rng
        if rng.random() < 0.18:
            for key in rng.sample(PRE_ATTRIBUTES, rng.choice((1, 1, 2))):
                node.attrs[key] = self.condition(1)
        if rng.random() < 0.18:
            for key in rng.sample(POST_ATTRIBUTES, rng.choice((1, 1, 2))):
                node.attrs[key] = self.action(1)

    # ------------------------------------------------------------------ cases

    def initial(self) -> list[tuple[str, str, object]]:
        rng = self.rng
        init: list[tuple[str, str, object]] = []
        for key in INT_VARS:
            init.append((key, "int", rng.randint(0, 2)))
        for key in BOOL_VARS:
            init.append((key, "bool", rng.random() < 0.5))
        init.append(("s0", "str", rng.choice(("a", "b", "ax"))))
        init.append(("k0", "int", rng.randint(1, 3)))
        return init

    def schedule(self) -> list[str]:
        rng = self.rng
        steps = [TICK] * rng.randint(3, 8)
        if rng.random() < 0.2:  # some ticks without the wake-up re-ticks
            steps = [TICK_EXACTLY_ONCE if rng.random() < 0.4 else step for step in steps]
        if rng.random() < 0.3:
            steps.insert(rng.randint(1, len(steps) - 1), HALT)
        if rng.random() < 0.5:
            steps.append(HALT)
        return steps

    def case(self) -> Case:
        max_depth = self.rng.randint(2, 5)
        main = self.node(1, max_depth)
        return Case(main=main, subtrees=dict(sorted(self.subtrees.items())),
                    init=self.initial(), schedule=self.schedule(), seed=self.seed)


def generate(seed: int, enabled: Collection[str] | None = None) -> Case:
    """The case of ``seed`` (the same seed always gives the same case)."""
    return Generator(seed, enabled).case()


def cases(first_seed: int, count: int, enabled: Collection[str] | None = None,
          keep: Callable[[Case], bool] | None = None) -> list[Case]:
    out = []
    for seed in range(first_seed, first_seed + count):
        case = generate(seed, enabled)
        if keep is None or keep(case):
            out.append(case)
    return out
