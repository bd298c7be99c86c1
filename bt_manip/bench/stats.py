"""Statistics over a bench's episodes: success rate with its 95 % interval, times, failures.

:func:`summarise` condenses the :class:`~bt_manip.bench.episodes.EpisodeResult` of every
episode into a :class:`BenchSummary`, which prints itself (:meth:`BenchSummary.text`) and is
written as summary.json.
"""

from __future__ import annotations

import math
from collections import Counter
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from bt_manip.bench.episodes import EpisodeResult

if TYPE_CHECKING:
    from bt_manip.episode import EpisodeSpec

LOCALIZATION_FIELDS = ("mean_error_m", "p95_error_m", "max_error_m", "mean_yaw_error_rad",
                       "time_over_0_2m_s")
"""The run report's localisation errors, each summed up over the episodes that localised."""
LEAVES_SHOWN = 12
"""Leaves listed in the text summary (summary.json has them all)."""


def wilson_interval(successes: int, n: int, z: float = 1.959964) -> tuple[float, float]:
    """95 % Wilson score interval of a binomial proportion (0..1)."""
    if n == 0:
        return (0.0, 1.0)
    p = successes / n
    denom = 1 + z * z / n
    centre = (p + z * z / (2 * n)) / denom
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / denom
    return (max(0.0, centre - half), min(1.0, centre + half))


@dataclass
class BenchSummary:
    """Statistics over all episodes."""

    runs: int
    successes: int
    success_rate: float
    ci95: tuple[float, float]
    sim_time: dict[str, float]
    wall_time: dict[str, float]
    real_time_factor: dict[str, float]
    failures: list[dict[str, Any]]
    injected: dict[str, int]
    metrics: dict[str, dict[str, float]] = field(default_factory=dict)
    leaf_failures: list[dict[str, Any]] = field(default_factory=list)
    """Per action that failed in some episode: its path, the episodes it failed in, the
    times."""
    tree: str = ""
    world: str = ""
    first_seed: int = 0
    inject: list[str] = field(default_factory=list)
    localization: dict[str, dict[str, float]] | None = None
    """With localisation on: per error of the run reports' ``localization`` (mean_error_m,
    ...), its statistics over the episodes; None (left out of summary.json) otherwise."""

    def text(self) -> str:
        lo, hi = self.ci95
        lines = [
            f"success: {self.successes}/{self.runs} = {self.success_rate * 100:.1f} % "
            f"(95 % interval {lo * 100:.1f}-{hi * 100:.1f} %)",
            f"sim time per episode: mean {self.sim_time['mean']:.1f} s, median "
            f"{self.sim_time['median']:.1f} s, p95 {self.sim_time['p95']:.1f} s",
            f"wall time per episode: mean {self.wall_time['mean']:.2f} s, median "
            f"{self.wall_time['median']:.2f} s; real-time factor median "
            f"{self.real_time_factor['median']:.1f}x",
        ]
        for name, st in sorted(self.metrics.items()):
            lines.append(
                f"blackboard {name}: mean {st['mean']:g}, min {st['min']:g}, max {st['max']:g}"
            )
        if self.localization is not None:
            err, p95 = self.localization["mean_error_m"], self.localization["p95_error_m"]
            yaw = self.localization["mean_yaw_error_rad"]
            lines.append(
                f"localisation error: mean {err['mean'] * 100:.1f} cm (episodes' p95 "
                f"{p95['mean'] * 100:.1f} cm on average), mean yaw error {yaw['mean']:.4f} rad"
            )
        if self.injected:
            lines.append(
                "faults injected: "
                + ", ".join(f"{k} x{v}" for k, v in sorted(self.injected.items()))
            )
        for f in self.failures:
            lines.append(f"  {f['count']:3d} x {f['node'] or '-'}: {f['reason']}")
        if self.leaf_failures:
            lines.append("actions that failed (episodes, times):")
            for f in self.leaf_failures[:LEAVES_SHOWN]:
                lines.append(f"  {f['episodes']:3d} {f['times']:4d}  {f['path']}")
            if len(self.leaf_failures) > LEAVES_SHOWN:
                lines.append(f"  ... {len(self.leaf_failures) - LEAVES_SHOWN} more in "
                             "summary.json")
        return "\n".join(lines)


def _stats(values: list[float]) -> dict[str, float]:
    if not values:
        return {"mean": 0.0, "median": 0.0, "p95": 0.0, "min": 0.0, "max": 0.0}
    a = np.asarray(values, dtype=float)
    return {
        "mean": float(a.mean()),
        "median": float(np.median(a)),
        "p95": float(np.percentile(a, 95)),
        "min": float(a.min()),
        "max": float(a.max()),
    }


def summarise(results: list[EpisodeResult], base: EpisodeSpec) -> BenchSummary:
    n = len(results)
    wins = sum(r.success for r in results)
    failures = Counter((r.failed_node, r.reason) for r in results if not r.success)
    injected = Counter(e["kind"] for r in results for e in r.injected)
    rtf = [r.sim_time / r.wall_time for r in results if r.wall_time > 0]
    names = sorted({k for r in results for k in r.metrics})
    metrics = {k: _stats([r.metrics[k] for r in results if k in r.metrics]) for k in names}
    episodes: Counter[str] = Counter(p for r in results for p in r.leaf_failures)
    times: Counter[str] = Counter()
    for r in results:
        times.update(r.leaf_failures)
    leaves = [{"path": p, "episodes": c, "times": times[p]}
              for p, c in sorted(episodes.items(), key=lambda kv: (-kv[1], -times[kv[0]]))]
    return BenchSummary(
        runs=n,
        successes=wins,
        success_rate=wins / n if n else 0.0,
        ci95=wilson_interval(wins, n),
        sim_time=_stats([r.sim_time for r in results]),
        wall_time=_stats([r.wall_time for r in results]),
        real_time_factor=_stats(rtf),
        failures=[{"node": k[0], "reason": k[1], "count": c} for k, c in failures.most_common()],
        injected=dict(injected),
        metrics=metrics,
        leaf_failures=leaves,
        tree=base.tree,
        world=base.world or "",
        first_seed=base.seed,
        inject=[f.text() for f in base.inject],
        localization=_localization_stats(results),
    )


def _localization_stats(results: list[EpisodeResult]) -> dict[str, dict[str, float]] | None:
    """Statistics of each localisation error over the episodes that localised (None when
    none did)."""
    located = [r.localization for r in results if r.localization]
    if not located:
        return None
    return {k: _stats([loc[k] for loc in located if k in loc]) for k in LOCALIZATION_FIELDS}
