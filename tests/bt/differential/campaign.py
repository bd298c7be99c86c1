"""Running many cases on both engines: agreement figures, shrunk mismatches grouped by cause.

Used by ``tests/bt/test_differential.py`` and ``benchmarks/btcpp_differential.py``.

Delay is generated only with ``BTM_DIFF_DELAY=1`` (see ``rules.NOT_GENERATED``): BT.CPP's
Delay starts a timer thread even for 0 ms, and whether it fires before ``tickOnce`` looks at
the wake-up signal is a race (BT.CPP then returns RUNNING instead of going on: about 0.5 % of
runs on an idle machine, far more under load), as is whether it fires before the Delay itself
looks. A case with a Delay is run on the oracle with each ``tickOnce`` giving the timer time to
fire (2 ms, then 20 ms, then 200 ms while bt-manip disagrees); bt-manip agrees if it matches
one of these runs.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Collection
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from bt_manip.bt.registry import NodeRegistry
from differential.btmanip_runner import make_registry, run_case
from differential.causes import cause_of
from differential.compare import Divergence, first_divergence, step_table
from differential.generator import generate
from differential.oracle import Oracle
from differential.rules import Rule, active_rules, enabled_builtins
from differential.shrink import shrink
from differential.spec import Case

TIMERS = ("Delay",)  # nodes whose 0 ms timer thread races BT.CPP's tickOnce
SETTLE_MS = (2, 20, 200)


@dataclass
class Mismatch:
    """A case on which the engines disagree, and its shrunk form."""

    case: Case
    divergence: Divergence
    shrunk: Case
    shrunk_divergence: Divergence
    oracle: dict[str, Any]
    btmanip: dict[str, Any]

    @property
    def cause(self) -> str:
        """A grouping key (see :mod:`differential.causes`)."""
        return cause_of(self.shrunk, self.oracle, self.btmanip, self.shrunk_divergence)

    def report(self) -> str:
        """The minimal XML, the schedule, the starting entries and what each engine did."""
        return "\n".join([
            f"seed {self.case.seed}; shrunk from {len(self.case.nodes())} to "
            f"{len(self.shrunk.nodes())} nodes",
            self.shrunk.pretty(),
            f"schedule: {', '.join(self.shrunk.schedule)}",
            f"initial blackboard: {self.shrunk.init_text()}",
            self.shrunk_divergence.describe(),
            step_table(self.oracle, self.btmanip),
        ])


@dataclass
class Report:
    """Figures of one campaign."""

    total: int = 0
    agree: int = 0
    excluded: Counter[str] = field(default_factory=Counter)
    mismatches: list[Mismatch] = field(default_factory=list)
    unshrunk: int = 0  # mismatches counted but not shrunk (over the shrink limit)
    not_generated: set[str] = field(default_factory=set)
    oracle_restarts: int = 0

    def by_cause(self) -> dict[str, list[Mismatch]]:
        groups: dict[str, list[Mismatch]] = {}
        for m in self.mismatches:
            groups.setdefault(m.cause, []).append(m)
        return dict(sorted(groups.items(), key=lambda item: -len(item[1])))

    def figures(self) -> dict[str, Any]:
        return {
            "total": self.total, "agree": self.agree,
            "mismatch": self.total - self.agree - sum(self.excluded.values()),
            "excluded": dict(self.excluded),
            "mismatches_by_cause": {cause: len(ms) for cause, ms in self.by_cause().items()},
            "unshrunk": self.unshrunk,
            "not_generated": sorted(self.not_generated),
            "oracle_restarts": self.oracle_restarts,
        }


class Differential:
    """Both engines, ready to run cases: the oracle worker and bt-manip's registry."""

    def __init__(self, oracle: Oracle, reg: NodeRegistry | None = None,
                 rules: list[Rule] | None = None) -> None:
        self.oracle = oracle
        self.reg = reg or make_registry()
        self.rules = active_rules() if rules is None else rules

    def compare(self, case: Case) -> tuple[Divergence | None, dict[str, Any], dict[str, Any]]:
        """The first divergence (None: they agree), BT.CPP's result and bt-manip's."""
        btmanip = run_case(case, self.reg)
        timers = any(n.tag in TIMERS for n in case.nodes())
        for settle in SETTLE_MS if timers else (0,):
            oracle = self.oracle.run(case, settle)
            div = first_divergence(oracle, btmanip)
            if div is None:
                break
        return div, oracle, btmanip

    def excluded_by(self, case: Case, oracle: dict[str, Any], btmanip: dict[str, Any],
                    div: Divergence) -> Rule | None:
        for rule in self.rules:
            if rule.applies(case, oracle, btmanip, div, self.reg):
                return rule
        return None

    def shrink(self, case: Case, div: Divergence, oracle: dict[str, Any],
               btmanip: dict[str, Any], budget: int = 600) -> Mismatch:
        """Shrink ``case`` keeping a mismatch of the same kind that no rule explains."""
        last: dict[int, tuple[Divergence, dict[str, Any], dict[str, Any]]] = {
            id(case): (div, oracle, btmanip)}

        def still_fails(candidate: Case) -> bool:
            d, o, b = self.compare(candidate)
            if (d is not None and d.kind == div.kind
                    and self.excluded_by(candidate, o, b, d) is None):
                last[id(candidate)] = (d, o, b)
                return True
            return False

        small = shrink(case, still_fails, budget)
        d, o, b = last[id(small)]
        return Mismatch(case, div, small, d, o, b)


def run_campaign(first_seed: int, count: int, shrink_limit: int = 50,
                 enabled: Collection[str] | None = None, oracle: Oracle | None = None,
                 reg: NodeRegistry | None = None) -> Report:
    """Generate ``count`` cases from ``first_seed`` on, run both engines, shrink mismatches.

    At most ``shrink_limit`` mismatches are shrunk; the others are counted in ``unshrunk``.
    """
    report = Report()
    if enabled is None:
        enabled, report.not_generated = enabled_builtins()
    own = oracle is None
    oracle = oracle or Oracle()
    try:
        diff = Differential(oracle, reg)
        for seed in range(first_seed, first_seed + count):
            case = generate(seed, enabled)
            report.total += 1
            div, o, b = diff.compare(case)
            if div is None:
                report.agree += 1
                continue
            rule = diff.excluded_by(case, o, b, div)
            if rule is not None:
                report.excluded[rule.name] += 1
                continue
            if len(report.mismatches) < shrink_limit:
                report.mismatches.append(diff.shrink(case, div, o, b))
            else:
                report.unshrunk += 1
        report.oracle_restarts = oracle.restarts
    finally:
        if own:
            oracle.close()
    return report


def write_mismatch_files(report: Report, directory: Path) -> list[Path]:
    """One ``NNN.md`` per cause (earlier ``NNN.md`` files are replaced); returns the paths."""
    directory.mkdir(parents=True, exist_ok=True)
    for old in directory.glob("[0-9][0-9][0-9].md"):
        old.unlink()
    paths = []
    for number, (cause, group) in enumerate(report.by_cause().items(), start=1):
        smallest = min(group, key=lambda m: m.shrunk.size())
        seeds = ", ".join(str(m.case.seed) for m in group[:20])
        text = "\n".join([
            f"# {cause}", "",
            f"{len(group)} of the shrunk mismatches (seeds {seeds}).", "",
            "```", smallest.report(), "```", "",
        ])
        path = directory / f"{number:03d}.md"
        path.write_text(text)
        paths.append(path)
    return paths
