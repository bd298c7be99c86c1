"""Tree coverage of a bench: which nodes, branches and recoveries its episodes really ran.

Each episode's record carries, per node it ticked (by path, so the instances of a SubTree count
apart), the counts of :mod:`bt_manip.run.node_counts`: ticks, SUCCESS, FAILURE, SKIPPED, halted
while RUNNING. :func:`bench_coverage` sums them over the episodes and lays them on the tree's
*outline* (:func:`tree_outline`: every node with its XML file and line, ticked or not), so the
result depends only on the episodes' records: a bench run with one process, two, on Ray, or
interrupted and resumed, gives the same coverage for the same seeds.

Branch nodes and their branches (a branch *ran* in an episode when its child was ticked; it
*won* when the child returned SUCCESS):

- Fallback, AsyncFallback, ReactiveFallback, Nav2's RecoveryNode and RoundRobin: every child;
  the children after the first are *recoveries* (what runs when the first fails);
- IfThenElse, WhileDoElse: the second child (then / do) and the third (else, a recovery); the
  first child, the condition, is not a branch;
- Switch2..Switch6: every case and the default, each counted as a recovery.

Branch coverage is the share of branches that ran in at least one episode. The coverage is
written as ``coverage.json`` (:meth:`BenchCoverage.to_json`, documented by
docs/schemas/bench-coverage.schema.json), printed (:meth:`BenchCoverage.text`) and drawn
(:mod:`bt_manip.bench.coverage_plot`).
"""

from __future__ import annotations

import json
from collections.abc import Iterable
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from bt_manip.bench.episodes import SCHEMA_VERSION, EpisodeResult
from bt_manip.bt import load_tree
from bt_manip.bt.controls import Fallback, IfThenElse, ReactiveFallback, WhileDoElse, _Switch
from bt_manip.bt.walk import walk_nodes
from bt_manip.errors import InputError
from bt_manip.nav2.controls import RecoveryNode, RoundRobin
from bt_manip.plugins import import_modules
from bt_manip.run.node_counts import COUNT_FIELDS

if TYPE_CHECKING:
    from bt_manip.episode import EpisodeSpec

COVERAGE_NAME = "coverage.json"
RECOVERIES_SHOWN = 12
"""Recoveries never exercised that the text lists (coverage.json has them all)."""


@dataclass(frozen=True)
class Branch:
    """A child of a branch node that is one way the node can go."""

    child: int
    """The child's index among its parent's children."""
    role: str
    """``first``, ``recovery``, ``then``, ``do``, ``else``, ``case N`` or ``default``."""
    recovery: bool
    """Whether it runs only when the way before it did not (see the module docstring)."""


def branches_of(node: Any) -> list[Branch] | None:
    """The branches of ``node`` when it is a branch node, else None."""
    n = len(node.bt_children())
    if isinstance(node, RecoveryNode):
        return [Branch(0, "first", False), Branch(1, "recovery", True)][:n]
    if isinstance(node, Fallback | ReactiveFallback | RoundRobin):
        return [Branch(i, "first" if i == 0 else "recovery", i > 0) for i in range(n)]
    if isinstance(node, IfThenElse | WhileDoElse):
        first = "then" if isinstance(node, IfThenElse) else "do"
        return [Branch(1, first, False)] + ([Branch(2, "else", True)] if n > 2 else [])
    if isinstance(node, _Switch):
        return [Branch(i, f"case {i + 1}" if i < n - 1 else "default", True) for i in range(n)]
    return None


@dataclass(frozen=True)
class OutlineNode:
    """A node of the tree as the coverage shows it, ticked or not."""

    index: int
    path: str
    name: str
    node: str
    """Its registered ID (the tree ID for a SubTree)."""
    kind: str
    depth: int
    parent: int
    file: str
    line: int | None
    children: tuple[str, ...] = ()
    """The paths of its children, in order."""
    branches: tuple[Branch, ...] | None = None

    def where(self) -> str:
        """``file:line`` of the node in its XML (the file alone when the line is unknown)."""
        return f"{self.file}:{self.line}" if self.line else self.file


def tree_outline(spec: EpisodeSpec) -> list[OutlineNode]:
    """Every node of ``spec``'s tree (loaded without its world), in the order of
    :func:`bt_manip.bt.walk.walk_nodes`; InputError for a tree that does not load."""
    problems = import_modules(spec.imports)
    if problems:
        raise InputError(problems)
    tree = load_tree(spec.tree, tree_id=spec.tree_id, models=spec.models)
    return outline_of(tree, spec.tree)


def outline_of(tree: Any, source: str = "") -> list[OutlineNode]:
    """The outline of a loaded tree (``source``: the file named for nodes without one)."""
    walked = list(walk_nodes(tree.root))
    kids: dict[int, list[str]] = {}
    for w in walked:
        kids.setdefault(w.parent, []).append(w.path)
    out = []
    for w in walked:
        branches = branches_of(w.node)
        out.append(OutlineNode(
            w.index, w.path, w.name, w.node_id, str(getattr(w.node, "KIND", "")), w.depth,
            w.parent, str(getattr(w.node, "xml_file", None) or source),
            getattr(w.node, "xml_line", None), tuple(kids.get(w.index, [])),
            tuple(branches) if branches is not None else None))
    return out


@dataclass
class NodeTotals:
    """A node's counts summed over the episodes."""

    episodes: int = 0
    """Episodes in which it was ticked."""
    success_episodes: int = 0
    """Episodes in which it returned SUCCESS at least once."""
    counts: dict[str, int] = field(default_factory=lambda: dict.fromkeys(COUNT_FIELDS, 0))


@dataclass
class BenchCoverage:
    """The coverage of a bench (see the module docstring)."""

    outline: list[OutlineNode]
    totals: dict[str, NodeTotals]
    runs: int
    seeds: list[int]
    info: dict[str, Any] = field(default_factory=dict)
    """What the bench was (tree, tree_id, world, inject; sweep for a sweep's merge)."""

    def node(self, path: str) -> NodeTotals:
        return self.totals.get(path) or NodeTotals()

    def branch_rows(self) -> list[dict[str, Any]]:
        """One row per branch: its parent's outline node, the branch, its child's outline
        node, and the episodes it ran and won in."""
        rows = []
        for parent in self.outline:
            for b in parent.branches or ():
                if b.child >= len(parent.children):
                    continue
                child = self._by_path[parent.children[b.child]]
                totals = self.node(child.path)
                rows.append({"parent": parent, "branch": b, "child": child,
                             "episodes": totals.episodes, "won": totals.success_episodes})
        return rows

    def __post_init__(self) -> None:
        self._by_path = {n.path: n for n in self.outline}

    @property
    def branch_counts(self) -> tuple[int, int]:
        """(branches that ran in some episode, branches)."""
        rows = self.branch_rows()
        return sum(1 for r in rows if r["episodes"]), len(rows)

    @property
    def ratio(self) -> float:
        """Branch coverage, 0..1 (1 for a tree without branches)."""
        covered, total = self.branch_counts
        return covered / total if total else 1.0

    def never_exercised(self) -> list[dict[str, Any]]:
        """The recoveries that ran in no episode, in tree order."""
        return [r for r in self.branch_rows() if r["branch"].recovery and not r["episodes"]]

    def to_json(self) -> dict[str, Any]:
        """coverage.json (see docs/schemas/bench-coverage.schema.json)."""
        covered, total = self.branch_counts
        rows = self.branch_rows()
        recoveries = [r for r in rows if r["branch"].recovery]
        nodes = []
        for n in self.outline:
            t = self.node(n.path)
            nodes.append({"path": n.path, "name": n.name, "node": n.node, "kind": n.kind,
                          "file": n.file, "line": n.line, "parent": n.parent,
                          "episodes": t.episodes, "success_episodes": t.success_episodes,
                          **t.counts})
        branch_nodes = []
        for parent in self.outline:
            if parent.branches is None:
                continue
            mine = [r for r in rows if r["parent"] is parent]
            branch_nodes.append({
                "path": parent.path, "node": parent.node, "file": parent.file,
                "line": parent.line, "episodes": self.node(parent.path).episodes,
                "covered": sum(1 for r in mine if r["episodes"]), "total": len(mine),
                "branches": [_branch_json(r) for r in mine]})
        return {
            "schema_version": SCHEMA_VERSION,
            **self.info,
            "runs": self.runs,
            "seeds": self.seeds,
            "branch_coverage": {"covered": covered, "total": total,
                                "ratio": round(self.ratio, 6)},
            "node_coverage": {"ticked": sum(1 for n in self.outline
                                            if self.node(n.path).episodes),
                              "total": len(self.outline)},
            "recoveries": {"exercised": sum(1 for r in recoveries if r["episodes"]),
                           "total": len(recoveries),
                           "never_exercised": [_branch_json(r) for r in self.never_exercised()]},
            "nodes": nodes,
            "branch_nodes": branch_nodes,
        }

    def text(self) -> str:
        """The console summary: branch and node coverage, the recoveries never exercised."""
        return coverage_text(self.to_json())


def _branch_json(row: dict[str, Any]) -> dict[str, Any]:
    child: OutlineNode = row["child"]
    branch: Branch = row["branch"]
    return {"path": child.path, "node": child.node, "file": child.file, "line": child.line,
            "parent": row["parent"].path, "child": branch.child, "role": branch.role,
            "recovery": branch.recovery, "episodes": row["episodes"], "won": row["won"]}


def bench_coverage(outline: list[OutlineNode], results: Iterable[EpisodeResult],
                   info: dict[str, Any] | None = None) -> BenchCoverage:
    """The coverage of ``results`` (episode records) on ``outline``: sums in seed order."""
    ordered = sorted(results, key=lambda r: r.seed)
    totals: dict[str, NodeTotals] = {}
    for r in ordered:
        for path, row in r.coverage.items():
            t = totals.setdefault(path, NodeTotals())
            if row and row[0]:
                t.episodes += 1
            if len(row) > 1 and row[1]:
                t.success_episodes += 1
            for name, value in zip(COUNT_FIELDS, row, strict=False):
                t.counts[name] += int(value)
    return BenchCoverage(outline, totals, len(ordered), [r.seed for r in ordered],
                         dict(info or {}))


def coverage_info(spec: EpisodeSpec) -> dict[str, Any]:
    """What coverage.json says of the bench it covers."""
    return {"tree": spec.tree, "tree_id": spec.tree_id, "world": spec.world or "",
            "inject": [f.text() for f in spec.inject]}


def write_coverage(coverage: BenchCoverage, folder: Path) -> None:
    """``folder``/coverage.json."""
    (Path(folder) / COVERAGE_NAME).write_text(json.dumps(coverage.to_json(), indent=2) + "\n")


def read_coverage(folder: str | Path) -> dict[str, Any]:
    """``folder``/coverage.json (a bench's or a sweep's folder, or the file itself);
    InputError when there is none or it is not one."""
    path = Path(folder)
    if path.is_dir():
        path = path / COVERAGE_NAME
    where = str(path)
    if not path.is_file():
        raise InputError.single(where, None, "no coverage.json here: run `bt-manip bench` "
                                "(or `bt-manip bench --resume` to finish one) first")
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
        if not isinstance(data, dict) or "branch_coverage" not in data:
            raise ValueError("no branch_coverage")
    except (OSError, ValueError) as exc:
        raise InputError.single(where, None, f"not a bench's coverage.json: {exc}") from None
    if data.get("schema_version") != SCHEMA_VERSION:
        raise InputError.single(where, None, f"schema version {data.get('schema_version')!r}; "
                                f"this bt-manip reads {SCHEMA_VERSION}")
    return data


def _percent(covered: int, total: int) -> str:
    return f"{100.0 * covered / total:.1f} %" if total else "no branches"


def coverage_text(data: dict[str, Any], shown: int = RECOVERIES_SHOWN) -> str:
    """The summary of a coverage.json: branches covered / total, nodes ticked, and each
    recovery that never ran with its path and XML line."""
    b, n, rec = data["branch_coverage"], data["node_coverage"], data["recoveries"]
    lines = [f"coverage: {b['covered']}/{b['total']} branches ran "
             f"({_percent(b['covered'], b['total'])}), {n['ticked']}/{n['total']} nodes "
             f"ticked, {rec['exercised']}/{rec['total']} recoveries exercised "
             f"in {data['runs']} episodes"]
    never = rec["never_exercised"]
    if never:
        lines.append(f"recoveries never exercised ({len(never)}):")
        ran = {node["path"]: node["episodes"] for node in data["nodes"]}
        for r in never[:shown]:
            where = f"{r['file']}:{r['line']}" if r.get("line") else r["file"]
            note = "" if ran.get(r["parent"]) else "; its parent never ran"
            lines.append(f"  {r['path']} [{r['node']}] {where} ({r['role']} of "
                         f"{r['parent'].rsplit('/', 1)[-1]}{note})")
        if len(never) > shown:
            lines.append(f"  ... {len(never) - shown} more in coverage.json")
    return "\n".join(lines)


def coverage_diff(a: dict[str, Any], b: dict[str, Any], names: tuple[str, str] = ("A", "B")
                  ) -> str:
    """How the coverage ``b`` differs from ``a`` (both coverage.json, named ``names``): branch
    coverage, and each branch (by path) that ran in one only or in a different number of
    episodes."""
    ba, bb = a["branch_coverage"], b["branch_coverage"]
    lines = [f"branch coverage: {ba['covered']}/{ba['total']} "
             f"({_percent(ba['covered'], ba['total'])}, {a['runs']} episodes) in {names[0]} -> "
             f"{bb['covered']}/{bb['total']} ({_percent(bb['covered'], bb['total'])}, "
             f"{b['runs']} episodes) in {names[1]}"]

    def branches(data: dict[str, Any]) -> dict[str, dict[str, Any]]:
        return {br["path"]: br for bn in data["branch_nodes"] for br in bn["branches"]}

    first, second = branches(a), branches(b)
    gained = [p for p in second if second[p]["episodes"] and not first.get(p, {}).get("episodes")]
    lost = [p for p in first if first[p]["episodes"] and not second.get(p, {}).get("episodes")]
    changed = [p for p in first if p in second and p not in gained and p not in lost
               and first[p]["episodes"] != second[p]["episodes"]]
    only_a = [p for p in first if p not in second]
    only_b = [p for p in second if p not in first]
    for title, paths in ((f"ran in {names[1]} only", gained), (f"ran in {names[0]} only", lost)):
        if paths:
            lines.append(f"{title} ({len(paths)}):")
            lines.extend(f"  {p} [{(second.get(p) or first[p])['role']}]" for p in paths)
    if changed:
        lines.append(f"episodes each branch ran in ({names[0]} -> {names[1]}):")
        lines.extend(f"  {first[p]['episodes']:4d} -> {second[p]['episodes']:4d}  {p}"
                     for p in changed)
    if only_a or only_b:
        lines.append(f"branches of one tree only: {len(only_a)} in {names[0]}, {len(only_b)} "
                     f"in {names[1]} (the trees differ)")
    if len(lines) == 1:
        lines.append("the same branches ran in the same number of episodes")
    return "\n".join(lines)


def branches_text(data: dict[str, Any]) -> str:
    """Every branch of a coverage.json: the episodes it ran and won in, by branch node."""
    lines = []
    for bn in data["branch_nodes"]:
        where = f"{bn['file']}:{bn['line']}" if bn.get("line") else bn["file"]
        lines.append(f"{bn['path']} [{bn['node']}] {where}: {bn['covered']}/{bn['total']} "
                     f"branches ran (the node ran in {bn['episodes']} episodes)")
        for br in bn["branches"]:
            lines.append(f"  {br['episodes']:4d} ran {br['won']:4d} won  {br['role']:<9} "
                         f"{br['path'].rsplit('/', 1)[-1]} [{br['node']}]")
    return "\n".join(lines)
