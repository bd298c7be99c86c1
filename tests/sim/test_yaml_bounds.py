"""The count of a YAML file's values, aliases expanded, on the parser's events: it refuses what
the count on composed nodes refuses, at a value that passes the limit, before anything is
composed."""

from __future__ import annotations

import random
from pathlib import Path

import pytest
import yaml

from bt_manip.errors import InputError
from bt_manip.sim import yaml_lines
from bt_manip.sim.yaml_lines import MAX_YAML_NODES, check_events, check_size, load_yaml


def _walls(n: int) -> str:
    return "name: many\nwalls:\n" + "".join(
        f"  - {{name: w{i}, from: [0, {i}], to: [1, {i}]}}\n" for i in range(n))


def test_a_megabyte_of_walls_is_refused_before_it_is_composed(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    path = tmp_path / "walls.yaml"
    path.write_text(_walls(15_000))  # 15,000 x 7 values in list 'walls', line 3
    assert path.stat().st_size < yaml_lines.MAX_YAML_BYTES

    def no_composing(self: object) -> None:
        raise AssertionError("composed before the count refused it")

    monkeypatch.setattr(yaml_lines._Loader, "get_single_node", no_composing)
    with pytest.raises(InputError) as err:
        load_yaml(path)
    (problem,) = err.value.problems
    assert (problem.file, problem.line) == (str(path), 3)
    assert problem.message.startswith(f"refused YAML: more than {MAX_YAML_NODES} values")


def _document(rng: random.Random) -> str:
    """A random document of anchors and aliases around the limit."""
    n_anchors = rng.randint(1, 4)
    lines = []
    for a in range(n_anchors):
        width = rng.choice([3, 10, 100, 1000])
        if a == 0:
            lines.append(f"a0: &a0 [{', '.join(['0'] * width)}]")
        else:
            uses = rng.randint(1, 40)
            lines.append(f"a{a}: &a{a} [" + ", ".join(
                [f"*a{rng.randrange(a)}" for _ in range(uses)] + ["1"] * rng.randint(0, 5)) + "]")
    uses = rng.randint(0, 400)
    lines.append("top: [" + ", ".join(f"*a{rng.randrange(n_anchors)}" for _ in range(uses)) + "]")
    lines.append("nested: {x: [1, 2, {y: *a0}]}")
    return "\n".join(lines) + "\n"


def _size_refusal(text: str) -> tuple[int | None, set[int]]:
    """The line check_size refuses (None: it accepts), and the lines of every container that
    holds more than the limit, aliases expanded."""
    root = yaml.compose(text, Loader=yaml_lines._Loader)
    sizes: dict[int, int] = {}

    def size(node: yaml.Node) -> int:
        if id(node) not in sizes:
            parts = ([p for pair in node.value for p in pair] if isinstance(node, yaml.MappingNode)
                     else node.value if isinstance(node, yaml.SequenceNode) else [])
            sizes[id(node)] = 1 + sum(size(p) for p in parts)
        return sizes[id(node)]

    over: set[int] = set()
    stack, seen = [root], set()
    while stack:
        node = stack.pop()
        if id(node) in seen:
            continue
        seen.add(id(node))
        if size(node) > MAX_YAML_NODES:
            over.add(node.start_mark.line + 1)
        if isinstance(node, yaml.MappingNode):
            stack.extend(p for pair in node.value for p in pair)
        elif isinstance(node, yaml.SequenceNode):
            stack.extend(node.value)
    try:
        check_size(root)
    except yaml.MarkedYAMLError as exc:
        assert exc.problem_mark is not None
        return exc.problem_mark.line + 1, over
    return None, over


def _event_refusal(text: str) -> int | None:
    try:
        check_events(text)
    except yaml.MarkedYAMLError as exc:
        assert exc.problem_mark is not None
        return exc.problem_mark.line + 1
    return None


def test_the_two_counts_refuse_the_same_documents_at_a_value_past_the_limit() -> None:
    rng = random.Random(7)
    refused = 0
    for _ in range(150):
        text = _document(rng)
        by_size, over = _size_refusal(text)
        by_events = _event_refusal(text)
        assert (by_events is None) == (by_size is None), text[:300]
        assert by_events is None or by_events in over, text[:300]
        refused += by_size is not None
    assert 20 < refused < 130  # both sides of the limit were tried
