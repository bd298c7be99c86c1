"""YAML loading that remembers where each value came from.

World files are user input: every complaint about them names the file and line, and every
file is bounded (:data:`MAX_YAML_BYTES`, and :data:`MAX_YAML_NODES` values once aliases are
expanded). PyYAML's safe loader is extended so that mappings become :class:`LineDict` (a dict
that knows the line of itself and of each key) and sequences become :class:`LineList` (a list
that knows the line of each item).
"""

from __future__ import annotations

import copy
import math
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import yaml

from bt_manip.cache import Memo, bytes_key
from bt_manip.errors import InputError, Problem
from bt_manip.input_files import read_bounded


class LineDict(dict):
    """A mapping read from YAML, with ``line`` (1-based) and ``key_lines[key]``."""

    line: int = 0
    key_lines: dict[str, int]

    def line_of(self, key: str) -> int:
        return self.key_lines.get(key, self.line)


class LineList(list):
    """A sequence read from YAML, with ``line`` and ``item_lines[i]``."""

    line: int = 0
    item_lines: list[int]

    def line_of(self, index: int) -> int:
        return self.item_lines[index] if index < len(self.item_lines) else self.line


MAX_YAML_BYTES = 1024 * 1024
MAX_YAML_NODES = 100_000


class _TooManyNodes(yaml.composer.ComposerError):
    """A value (at ``mark``) whose count, aliases expanded, passes :data:`MAX_YAML_NODES`."""

    def __init__(self, mark: yaml.Mark) -> None:
        super().__init__(
            None, None, f"more than {MAX_YAML_NODES} values (the limit of a YAML input; each "
            "use of an alias counts as a copy of what it names)", mark)


_BaseLoader: type = getattr(yaml, "CSafeLoader", yaml.SafeLoader)  # libyaml when installed


class _Loader(_BaseLoader):  # type: ignore[misc, valid-type]
    """Safe loader that keeps line numbers and refuses duplicate keys (libyaml's parser when
    available: pure-Python PyYAML takes several seconds for a 1 MB file)."""


def check_size(root: yaml.Node) -> None:
    """Refuse a composed document whose values, aliases expanded, pass :data:`MAX_YAML_NODES`.

    Composing shares the node an alias names, so the graph is as small as the file; its
    expanded size is counted on the graph (each node once, bottom-up, without recursion) and
    the first node whose size passes the limit is refused, before any value is constructed.
    A value that contains itself through an alias is refused too.
    """
    sizes: dict[int, int] = {}
    opened: set[int] = set()  # nodes whose children are being counted
    stack: list[tuple[yaml.Node, bool]] = [(root, False)]
    while stack:
        node, children_done = stack.pop()
        key = id(node)
        if children_done:
            opened.discard(key)
            size = 1 + sum(sizes[id(child)] for child in _children(node))
            if size > MAX_YAML_NODES:
                raise _TooManyNodes(node.start_mark)
            sizes[key] = size
            continue
        if key in sizes:
            continue
        if key in opened:  # reached again from below itself
            raise yaml.composer.ComposerError(
                None, None, "an alias refers to a value that contains it", node.start_mark)
        opened.add(key)
        stack.append((node, True))
        stack.extend((child, False) for child in _children(node) if id(child) not in sizes)


def check_events(text: str) -> None:
    """Refuse ``text`` early when its values, aliases expanded, pass :data:`MAX_YAML_NODES`:
    counted on the parser's events, which cost a tenth of composing the document's nodes (a
    refusal of a 1 MB file then takes a fraction of a second, not seconds).

    The first container (in the file's order) to close holding more than the limit is
    refused, at its line; an alias counts what its anchor held when it closed. The counts are
    :func:`check_size`'s, so the two refuse the same files (at the same container, unless
    several pass the limit). Malformed YAML, and an alias used inside the value it names, are
    left to the composer and :func:`check_size`."""
    events = yaml.parse(text, Loader=_BaseLoader)
    held: dict[str, int] = {}  # values of each closed anchor
    open_: list[list[Any]] = []  # [count so far, anchor, start mark] of each open container
    while True:
        try:
            event = next(events)
        except StopIteration:
            return
        except yaml.YAMLError:
            return  # the composer reports it, with its line
        if isinstance(event, yaml.CollectionStartEvent):
            open_.append([1, event.anchor, event.start_mark])
            continue
        if isinstance(event, yaml.CollectionEndEvent):
            count, anchor, mark = open_.pop()
            if count > MAX_YAML_NODES:
                raise _TooManyNodes(mark)
        elif isinstance(event, yaml.ScalarEvent):
            count, anchor = 1, event.anchor
        elif isinstance(event, yaml.AliasEvent):
            count, anchor = held.get(event.anchor or "", 1), None
        else:
            continue
        if anchor is not None:
            held[anchor] = count
        if open_:
            open_[-1][0] += count


def _children(node: yaml.Node) -> list[yaml.Node]:
    if isinstance(node, yaml.MappingNode):
        return [part for pair in node.value for part in pair]
    if isinstance(node, yaml.SequenceNode):
        return list(node.value)
    return []


def _construct_mapping(loader: _Loader, node: yaml.MappingNode) -> LineDict:
    loader.flatten_mapping(node)
    out = LineDict()
    out.line = node.start_mark.line + 1
    out.key_lines = {}
    for key_node, value_node in node.value:
        key = loader.construct_object(key_node, deep=True)
        if not isinstance(key, str):
            key = str(key)
        if key in out:
            raise yaml.constructor.ConstructorError(
                None, None, f"duplicate key '{key}'", key_node.start_mark
            )
        out[key] = loader.construct_object(value_node, deep=True)
        out.key_lines[key] = key_node.start_mark.line + 1
    return out


def _construct_sequence(loader: _Loader, node: yaml.SequenceNode) -> LineList:
    out = LineList(loader.construct_object(child, deep=True) for child in node.value)
    out.line = node.start_mark.line + 1
    out.item_lines = [child.start_mark.line + 1 for child in node.value]
    return out


_Loader.add_constructor(yaml.resolver.BaseResolver.DEFAULT_MAPPING_TAG, _construct_mapping)
_Loader.add_constructor(yaml.resolver.BaseResolver.DEFAULT_SEQUENCE_TAG, _construct_sequence)


YAML_MEMO_ENTRIES = 32
YAML_MEMO_BYTES = 4 * 1024 * 1024
"""Files whose values are remembered for the process (:func:`load_yaml`): at most this many,
of at most this many bytes each."""

_YAML_MEMO: Memo[tuple[Any]] = Memo(YAML_MEMO_ENTRIES)


def load_yaml(path: str | Path) -> Any:
    """Read a YAML file; syntax errors become an InputError with the file and line.

    The file is read every time; the values of a file whose bytes were read before in this
    process are a copy of those read then (the same bytes give the same values), so a world
    loaded episode after episode is parsed once. A caller may change what it gets."""
    path = Path(path)
    return yaml_values(path, read_bounded(path, MAX_YAML_BYTES, "YAML file"))


def yaml_values(path: Path, data: bytes) -> Any:
    """The values of ``data``, the bytes of the YAML file ``path`` (as :func:`load_yaml`)."""
    key = bytes_key(data)
    known = _YAML_MEMO.get(key)
    if known is not None:
        return copy_values(known[0])
    values = _parse(path, data)
    if len(data) <= YAML_MEMO_BYTES // YAML_MEMO_ENTRIES:
        _YAML_MEMO.put(key, (copy_values(values),))
    return values


def copy_values(value: Any, memo: dict[int, Any] | None = None) -> Any:
    """A deep copy of values read from YAML: mappings and sequences copied with their lines,
    a value reached twice (through an alias) copied once and shared as in the original."""
    if memo is None:
        memo = {}
    kind = type(value)
    if kind in _IMMUTABLE:
        return value
    known = memo.get(id(value))
    if known is not None:
        return known
    if kind is LineDict:
        out = LineDict()
        memo[id(value)] = out
        out.line = value.line
        out.key_lines = dict(value.key_lines)
        for k, v in value.items():
            out[k] = copy_values(v, memo)
        return out
    if kind is LineList:
        seq = LineList()
        memo[id(value)] = seq
        seq.line = value.line
        seq.item_lines = list(value.item_lines)
        seq.extend(copy_values(v, memo) for v in value)
        return seq
    other = copy.deepcopy(value)  # other YAML types: sets, dates, byte strings
    memo[id(value)] = other
    return other


_IMMUTABLE = (str, int, float, bool, type(None))


def _parse(path: Path, data: bytes) -> Any:
    """The values of a YAML document (``data``, read from ``path``)."""
    text = data.decode("utf-8", errors="replace")
    loader = None
    try:
        check_events(text)
        loader = _Loader(text)
        root = loader.get_single_node()
        if root is None:
            return None
        check_size(root)
        return loader.construct_document(root)
    except yaml.MarkedYAMLError as exc:
        mark = exc.problem_mark or exc.context_mark
        line = mark.line + 1 if mark is not None else None
        what = exc.problem or exc.context or "invalid YAML"
        if exc.context and exc.problem:
            what = f"{exc.context}, {exc.problem}"
        if isinstance(exc, _TooManyNodes):
            raise InputError([Problem(str(path), line, f"refused YAML: {what}")]) from None
        raise InputError([Problem(str(path), line, f"invalid YAML: {what}")]) from None
    except yaml.reader.ReaderError as exc:
        line = text.count("\n", 0, exc.position) + 1
        what = f"character #x{exc.character:04x} is not allowed ({exc.reason})"
        if isinstance(exc.character, bytes):
            what = f"bytes that are not UTF-8 ({exc.reason})"
        raise InputError([Problem(str(path), line, f"invalid YAML: {what}")]) from None
    except yaml.YAMLError as exc:
        what = " ".join(str(exc).split())
        raise InputError([Problem(str(path), None, f"invalid YAML: {what}")]) from None
    finally:
        if loader is not None:
            loader.dispose()


def is_number(value: Any) -> bool:
    """A finite int or float read from YAML (booleans are not numbers)."""
    return isinstance(value, int | float) and not isinstance(value, bool) and math.isfinite(value)


def numbers_of(value: Any, n: int) -> tuple[float, ...] | None:
    """``value`` as ``n`` floats if it is a YAML list of ``n`` finite numbers, else None."""
    if isinstance(value, list) and len(value) == n and all(is_number(v) for v in value):
        return tuple(float(v) for v in value)
    return None


class ProblemCollector:
    """Base of the readers of YAML input files: records every problem with file and line."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self.problems: list[Problem] = []

    def fail(self, line: int | None, message: str) -> None:
        self.problems.append(Problem(str(self.path), line, message))

    def unknown_keys(self, d: LineDict, allowed: set[str], where: str) -> None:
        """One problem per key of ``d`` not in ``allowed``, with the closest known key."""
        import difflib

        for key in d:
            if key not in allowed:
                close = difflib.get_close_matches(key, sorted(allowed), n=1)
                hint = (
                    f"; did you mean '{close[0]}'?"
                    if close
                    else f"; allowed: {', '.join(sorted(allowed))}"
                )
                self.fail(d.line_of(key), f"unknown key '{key}' in {where}{hint}")


class FieldReader(ProblemCollector):
    """Typed readers of the fields of YAML input files (worlds, robot descriptors).

    Each reader converts one value and records a problem with the file and line when the value
    does not fit; the caller keeps going so that one run reports every problem of a file.
    """

    def mapping(self, value: Any, line: int, where: str) -> LineDict | None:
        """``value`` if it is a mapping, else None (and a problem)."""
        if isinstance(value, LineDict):
            return value
        self.fail(line, f"{where} must be a mapping, got {type(value).__name__}")
        return None

    def seq(self, value: Any, line: int, where: str) -> LineList | None:
        """``value`` if it is a list (absent = empty), else None (and a problem)."""
        if value is None:
            return LineList()
        if isinstance(value, LineList):
            return value
        self.fail(line, f"{where} must be a list, got {type(value).__name__}")
        return None

    def entries(
        self, items: LineList | None, where: str, allowed: set[str] | None = None
    ) -> Iterator[tuple[int, str, LineDict]]:
        """Index, place (``where[i]``) and mapping of each item of a list that is a mapping
        (each other item is a problem); with ``allowed``, unknown keys are problems too."""
        for i, raw in enumerate(items or []):
            here = f"{where}[{i}]"
            d = self.mapping(raw, items.line_of(i), here)  # type: ignore[union-attr]
            if d is None:
                continue
            if allowed is not None:
                self.unknown_keys(d, allowed, here)
            yield i, here, d

    def number(
        self,
        d: LineDict,
        key: str,
        where: str,
        default: float | None = None,
        positive: bool = False,
        non_negative: bool = False,
        minimum: float | None = None,
        within: tuple[float, float] | None = None,
    ) -> float | None:
        """``d[key]`` as a finite float; ``default`` when absent (required when None).

        A value out of its bounds (``positive``: > 0, ``non_negative``: >= 0, ``minimum``,
        ``within``: inclusive range) is a problem and gives ``default``.
        """
        if key not in d:
            if default is None:
                self.fail(d.line, f"{where} is missing '{key}'")
            return default
        value = d[key]
        if not is_number(value):
            self.fail(d.line_of(key), f"{where}.{key} must be a number, got {value!r}")
            return default
        if positive and value <= 0:
            self.fail(d.line_of(key), f"{where}.{key} must be > 0, got {value}")
            return default
        if non_negative and value < 0:
            self.fail(d.line_of(key), f"{where}.{key} must be >= 0, got {value}")
            return default
        if minimum is not None and value < minimum:
            self.fail(d.line_of(key), f"{where}.{key} must be >= {minimum}, got {value}")
            return default
        if within is not None and not within[0] <= value <= within[1]:
            self.fail(d.line_of(key),
                      f"{where}.{key} must be within {within[0]:g}..{within[1]:g}, got {value}")
            return default
        return float(value)

    def vector(self, value: Any, n: int, line: int, where: str) -> tuple[float, ...] | None:
        """``value`` as ``n`` floats if it is a list of ``n`` finite numbers, else None."""
        out = numbers_of(value, n)
        if out is None:
            self.fail(line, f"{where} must be a list of {n} numbers, got {value!r}")
        return out

    def text(self, d: LineDict, key: str, where: str, default: str | None = None) -> str:
        """``d[key]`` as a non-empty text ("" and a problem otherwise)."""
        value = d.get(key, default)
        if not isinstance(value, str) or not value:
            self.fail(d.line_of(key), f"{where}.{key} must be a name (text)")
            return ""
        return value

    def names(self, d: LineDict, key: str, where: str, required: bool = True) -> tuple[str, ...]:
        """``d[key]`` as a non-empty list of names (``()`` when absent and not ``required``)."""
        value = d.get(key)
        if value is None and not required:
            return ()
        if (
            not isinstance(value, list)
            or not value
            or not all(isinstance(v, str) and v for v in value)
        ):
            self.fail(d.line_of(key), f"{where}.{key} must be a non-empty list of names")
            return ()
        return tuple(value)
