"""``bench --sweep``: the same bench at several values of one fault or blackboard entry.

A sweep is an ``--inject`` text, or ``bb:KEY=VALUE``, with ``{a,b,c}`` in place of one value:
``slip:{0,0.1,0.2,0.3}``, ``Attach:failure:{0,0.5}``, ``bb:speed={0.2,0.4}``. Each value is one
point: the bench's episodes (the same seeds at every point, so the points differ only by the
swept value) with that fault added or that entry set. Each point has its own folder of bench
outputs under the sweep's ``--out``; the sweep adds ``sweep.json``, ``sweep.csv`` and
``sweep.png`` (the success rate and its 95 % interval against the swept value).
"""

from __future__ import annotations

import csv
import json
import math
import re
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

from bt_manip.bench.episodes import SCHEMA_VERSION
from bt_manip.bt.blackboard import bb_value
from bt_manip.errors import InputError
from bt_manip.run.faults import parse_fault

if TYPE_CHECKING:
    from bt_manip.bench.stats import BenchSummary
    from bt_manip.episode import EpisodeSpec

MAX_POINTS = 64
"""Values a sweep may have."""
PLAN_NAME = "sweep.json"
_BRACES = re.compile(r"\{([^{}]*)\}")


@dataclass(frozen=True)
class SweepPoint:
    """One value of a sweep: its text, the folder of its bench, and its episodes' spec."""

    value: str
    folder: str
    spec: EpisodeSpec


def _values(text: str) -> tuple[str, str, list[str]]:
    """``text`` split round its one ``{a,b,c}``: (before, after, values)."""
    found = _BRACES.findall(text)
    if len(found) != 1 or text.count("{") != 1 or text.count("}") != 1:
        raise InputError.single("--sweep", None, f"'{text}': put exactly one {{a,b,...}} in "
                                "place of a value, e.g. slip:{0,0.1,0.2}")
    values = [v.strip() for v in found[0].split(",")]
    if any(not v for v in values):
        raise InputError.single("--sweep", None, f"'{text}': an empty value in {{...}}")
    if len(set(values)) != len(values):
        raise InputError.single("--sweep", None, f"'{text}': a value is given twice")
    if len(values) > MAX_POINTS:
        raise InputError.single("--sweep", None,
                                f"'{text}': {len(values)} values; at most {MAX_POINTS}")
    before, _, after = text.partition("{" + found[0] + "}")
    return before, after, values


def _folder(index: int, value: str) -> str:
    return f"{index:02d}_" + (re.sub(r"[^A-Za-z0-9.=+-]+", "_", value)[:40] or "value")


def sweep_points(base: EpisodeSpec, text: str) -> list[SweepPoint]:
    """The points of the sweep ``text`` over the bench ``base``; InputError when the text is
    not a sweep or a value does not make a valid fault."""
    before, after, values = _values(text)
    points = []
    for i, value in enumerate(values):
        filled = before + value + after
        if filled.startswith("bb:"):
            key, sep, entry = filled[3:].partition("=")
            if not sep or not key.strip() or "{" in key or "}" in key:
                raise InputError.single("--sweep", None,
                                        f"'{text}': expected bb:KEY={{a,b,...}}")
            spec = replace(base, blackboard={**base.blackboard, key.strip(): bb_value(entry)})
        else:
            try:
                fault = parse_fault(filled)
            except InputError as exc:
                raise InputError.single(
                    "--sweep", None, f"value '{value}': {exc.problems[0].message}") from None
            spec = replace(base, inject=[*base.inject, fault])
        points.append(SweepPoint(value, _folder(i, value), spec))
    return points


def write_plan(out: Path, text: str, points: list[SweepPoint]) -> None:
    """``sweep.json`` as the sweep starts: which folder holds which value (``--resume``
    reads it)."""
    plan = {"schema_version": SCHEMA_VERSION, "sweep": text,
            "points": [{"value": p.value, "folder": p.folder} for p in points]}
    (out / PLAN_NAME).write_text(json.dumps(plan, indent=2) + "\n")


def read_plan(out: Path) -> tuple[str, list[tuple[str, str]]]:
    """The sweep text and the (value, folder) of each point of ``out``/sweep.json."""
    path = out / PLAN_NAME
    try:
        plan = json.loads(path.read_text())
        return str(plan["sweep"]), [(str(p["value"]), str(p["folder"])) for p in plan["points"]]
    except (OSError, ValueError, KeyError, TypeError) as exc:
        raise InputError.single(str(path), None, f"not a sweep plan: {exc}") from None


def _number(value: str) -> float | None:
    try:
        x = float(value)
    except ValueError:
        return None
    return x if math.isfinite(x) else None


def write_results(out: Path, text: str, rows: list[tuple[str, str, BenchSummary]]) -> None:
    """sweep.json (the plan with each point's statistics), sweep.csv and sweep.png."""
    points = []
    for value, folder, s in rows:
        points.append({"value": value, "folder": folder, "runs": s.runs,
                       "successes": s.successes, "success_rate": s.success_rate,
                       "ci95": list(s.ci95), "sim_time": s.sim_time,
                       "injected": s.injected, "metrics": s.metrics})
    summary = {"schema_version": SCHEMA_VERSION, "sweep": text, "points": points}
    (out / PLAN_NAME).write_text(json.dumps(summary, indent=2) + "\n")
    with open(out / "sweep.csv", "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["schema_version", "value", "runs", "successes", "success_rate", "ci95_low",
                    "ci95_high", "median_sim_time"])
        for p, (_, _, s) in zip(points, rows, strict=True):
            w.writerow([SCHEMA_VERSION, p["value"], s.runs, s.successes,
                        f"{s.success_rate:.4f}", f"{s.ci95[0]:.4f}", f"{s.ci95[1]:.4f}",
                        f"{s.sim_time['median']:.3f}"])
    figure = sweep_figure(text, rows)
    figure.savefig(out / "sweep.png", dpi=90)
    import matplotlib.pyplot as plt

    plt.close(figure)


def sweep_figure(text: str, rows: list[tuple[str, str, BenchSummary]]) -> Any:
    """Success rate (%) against the swept value, with the 95 % interval as error bars; a
    numeric axis when every value is a number, else one tick per value in sweep order."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    numbers = [_number(v) for v, _, _ in rows]
    numeric = all(n is not None for n in numbers)
    xs = [float(n) for n in numbers if n is not None] if numeric else list(range(len(rows)))
    rates = [100.0 * s.success_rate for _, _, s in rows]
    low = [max(0.0, r - 100.0 * s.ci95[0]) for r, (_, _, s) in zip(rates, rows, strict=True)]
    high = [max(0.0, 100.0 * s.ci95[1] - r) for r, (_, _, s) in zip(rates, rows, strict=True)]
    fig, ax = plt.subplots(figsize=(7, 4))
    ax.errorbar(xs, rates, yerr=[low, high], fmt="o-", capsize=4)
    if not numeric:
        ax.set_xticks(xs, [v for v, _, _ in rows])
    ax.set_ylim(-5, 105)
    ax.set_xlabel(f"swept value ({text})")
    ax.set_ylabel("success rate (%), 95 % interval")
    runs = rows[0][2].runs if rows else 0
    ax.set_title(f"{runs} episodes per value")
    fig.tight_layout()
    return fig
