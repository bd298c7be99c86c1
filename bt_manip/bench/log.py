"""A bench's episodes as they finish: ``episodes.jsonl``, and resuming an interrupted bench.

The file's first line is the bench itself (``"kind": "bench"``): the schema version, what
defines every episode (tree, world, blackboard entries, faults, run options, imports), the seeds
to run, and a SHA-256 digest of the tree and world files. Each further line is one finished
episode (``"kind": "episode"``, the fields of
:class:`~bt_manip.bench.episodes.EpisodeResult`), written
and flushed as soon as it finishes, so a bench that is interrupted (Ctrl-C, a lost machine)
keeps every episode it finished. A last line cut short by a crash is ignored on reading.

``bt-manip bench --resume DIR`` reads the file back (:func:`read_log`), runs the seeds that have
no line yet with the same definition, and appends them: the result is the bench that would
have run without the interruption. A tree or world file that changed since is refused.
"""

from __future__ import annotations

import hashlib
import json
import os
from dataclasses import asdict, dataclass, field, fields
from pathlib import Path
from typing import IO, Any

from bt_manip.bench.episodes import SCHEMA_VERSION, EpisodeResult
from bt_manip.episode import EpisodeSpec
from bt_manip.errors import InputError
from bt_manip.run.faults import parse_fault
from bt_manip.run.runner import RunOptions

LOG_NAME = "episodes.jsonl"
MAX_LOG_BYTES = 64 * 1024 * 1024
"""Largest episodes.jsonl that ``--resume`` reads."""


def digest(path: str | None) -> str:
    """SHA-256 of a file's bytes (empty text for no file)."""
    if not path:
        return ""
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def spec_to_json(spec: EpisodeSpec) -> dict[str, Any]:
    """What defines the episodes of a bench, as JSON (the seed and .btlog path excepted), with
    the folder that relative paths start from (``cwd``)."""
    data: dict[str, Any] = {
        "cwd": os.getcwd(),
        "tree": spec.tree,
        "world": spec.world,
        "tree_id": spec.tree_id,
        "models": list(spec.models),
        "blackboard": dict(spec.blackboard),
        "inject": [f.text() for f in spec.inject],
        "options": asdict(spec.options),
        "imports": list(spec.imports),
    }
    if spec.localize:  # absent when off: a bench without it writes what it always wrote
        data["localize"] = True
    return data


def spec_from_json(data: dict[str, Any]) -> EpisodeSpec:
    """The inverse of :func:`spec_to_json`; relative file paths are made relative to the
    current folder (the bench may be resumed from another one)."""
    start = Path(str(data.get("cwd") or "."))

    def here(path: str | None) -> str | None:
        if not path or Path(path).is_absolute() or start.resolve() == Path.cwd().resolve():
            return path
        return os.path.relpath(start / path)

    known = {f.name for f in fields(RunOptions)}
    options = RunOptions(**{k: v for k, v in dict(data.get("options", {})).items() if k in known})
    return EpisodeSpec(
        tree=str(here(str(data["tree"]))),
        world=here(data.get("world")),
        tree_id=data.get("tree_id"),
        models=[str(here(m)) for m in data.get("models", [])],
        blackboard=dict(data.get("blackboard", {})),
        inject=[parse_fault(t) for t in data.get("inject", [])],
        options=options,
        imports=[str(here(m)) if str(m).endswith(".py") else m
                 for m in data.get("imports", [])],
        localize=bool(data.get("localize", False)),
    )


@dataclass
class BenchHeader:
    """The first line of episodes.jsonl: the bench's definition."""

    spec: dict[str, Any]
    seeds: list[int]
    digests: dict[str, str] = field(default_factory=dict)
    schema_version: int = SCHEMA_VERSION

    @classmethod
    def of(cls, spec: EpisodeSpec, seeds: list[int]) -> BenchHeader:
        return cls(spec_to_json(spec), list(seeds),
                   {"tree": digest(spec.tree), "world": digest(spec.world)})

    def to_json(self) -> dict[str, Any]:
        return {"kind": "bench", "schema_version": self.schema_version, "seeds": self.seeds,
                "spec": self.spec, "digests": self.digests}


class BenchLog:
    """episodes.jsonl of one bench, open for appending finished episodes."""

    def __init__(self, path: Path, header: BenchHeader, fh: IO[str]) -> None:
        self.path = path
        self.header = header
        self._fh = fh

    @classmethod
    def create(cls, folder: Path, header: BenchHeader) -> BenchLog:
        """A new log in ``folder`` (an earlier one there is replaced)."""
        path = Path(folder) / LOG_NAME
        fh = open(path, "w", encoding="utf-8")  # noqa: SIM115  (closed by close())
        fh.write(json.dumps(header.to_json()) + "\n")
        fh.flush()
        return cls(path, header, fh)

    @classmethod
    def reopen(cls, folder: Path, header: BenchHeader, valid_bytes: int) -> BenchLog:
        """The log of ``folder`` for appending, cut back to its ``valid_bytes`` first bytes
        (a line left half-written by a crash goes)."""
        path = Path(folder) / LOG_NAME
        fh = open(path, "r+", encoding="utf-8")  # noqa: SIM115  (closed by close())
        fh.truncate(valid_bytes)
        fh.seek(valid_bytes)
        return cls(path, header, fh)

    def append(self, result: EpisodeResult) -> None:
        """Write one finished episode and flush it to the file."""
        self._fh.write(json.dumps({"kind": "episode", **result.to_json()}) + "\n")
        self._fh.flush()

    def close(self) -> None:
        self._fh.close()

    def __enter__(self) -> BenchLog:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


@dataclass
class LoggedBench:
    """What an episodes.jsonl holds: the header, the finished episodes, and how many of its
    bytes are whole lines."""

    header: BenchHeader
    spec: EpisodeSpec
    """The episodes' definition read from the header (relative paths made relative to here)."""
    results: list[EpisodeResult]
    valid_bytes: int

    @property
    def missing(self) -> list[int]:
        """The seeds of the bench that have no finished episode yet, in order."""
        done = {r.seed for r in self.results}
        return [s for s in self.header.seeds if s not in done]


def read_log(folder: str | Path) -> LoggedBench:
    """Read ``folder``/episodes.jsonl; InputError naming the file and line when it is not one."""
    path = Path(folder) / LOG_NAME
    where = str(path)
    if not path.is_file():
        raise InputError.single(where, None, "no episodes.jsonl here: nothing to resume")
    if path.stat().st_size > MAX_LOG_BYTES:
        raise InputError.single(where, None, f"larger than {MAX_LOG_BYTES} bytes")
    data = path.read_bytes()
    lines = data.split(b"\n")
    complete = lines[:-1]  # the part after the last newline is a line cut short (or empty)
    if not complete:
        raise InputError.single(where, 1, "empty: the bench's first line is missing")
    try:
        first = json.loads(complete[0])
        if first.get("kind") != "bench":
            raise ValueError("the first line is not the bench's (kind 'bench')")
        version = first.get("schema_version")
        if isinstance(version, int) and version < SCHEMA_VERSION:
            raise InputError.single(
                where, 1, f"written by an older bt-manip (format version {version}, whose "
                "episodes lack the per-node counts of coverage.json); resuming it would mix "
                f"two formats: start a new bench (this bt-manip writes version {SCHEMA_VERSION})")
        if version != SCHEMA_VERSION:
            raise ValueError(f"schema version {version!r}; this bt-manip reads {SCHEMA_VERSION}")
        header = BenchHeader(dict(first["spec"]), [int(s) for s in first["seeds"]],
                             dict(first.get("digests", {})))
        spec = spec_from_json(header.spec)
    except (ValueError, KeyError, TypeError) as exc:
        raise InputError.single(where, 1, f"not a bench log: {exc}") from None
    known = {f.name for f in fields(EpisodeResult)}
    results: dict[int, EpisodeResult] = {}
    valid = len(complete[0]) + 1
    for number, line in enumerate(complete[1:], start=2):
        try:
            row = json.loads(line)
            if row.get("kind") != "episode":
                raise ValueError("not an episode line")
            result = EpisodeResult(**{k: v for k, v in row.items() if k in known})
        except (ValueError, TypeError) as exc:
            if number == len(complete):  # the last line: a write cut short
                break
            raise InputError.single(where, number, f"not an episode: {exc}") from None
        results[result.seed] = result
        valid += len(line) + 1
    return LoggedBench(header, spec, sorted(results.values(), key=lambda r: r.seed), valid)


def check_unchanged(logged: LoggedBench, folder: str | Path) -> None:
    """InputError when the tree or world file differs from the one the bench started with."""
    for key in ("tree", "world"):
        path = getattr(logged.spec, key)
        if not path:
            continue
        if not Path(path).is_file():
            raise InputError.single(str(path), None,
                                    f"the bench in {folder} ran this {key} file; it is gone")
        recorded = logged.header.digests.get(key)
        if recorded and digest(path) != recorded:
            raise InputError.single(
                str(path), None,
                f"changed since the bench in {folder} started: resuming would mix two "
                f"{key}s (start a new bench instead)")
