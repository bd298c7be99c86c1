"""A bench's output files: episodes.json, episodes.csv, summary.json and outcomes.png.

(The output paths themselves are checked before the bench starts, by :mod:`bt_manip.outputs`;
episodes.jsonl, written as episodes finish, is :mod:`bt_manip.bench.log`'s.)
"""

from __future__ import annotations

import csv
import json
from dataclasses import asdict
from pathlib import Path
from typing import Any

from bt_manip.bench.episodes import SCHEMA_VERSION, EpisodeResult
from bt_manip.bench.stats import LOCALIZATION_FIELDS, BenchSummary
from bt_manip.outputs import make_folder

STATUS_COLOURS = {
    "SUCCESS": "tab:green",
    "FAILURE": "tab:red",
    "BUDGET": "tab:orange",
    "SKIPPED": "tab:olive",
    "ERROR": "tab:purple",
    "INTERRUPTED": "tab:grey",
}


def write_outputs(results: list[EpisodeResult], summary: BenchSummary, out: Path) -> None:
    """episodes.json, episodes.csv, summary.json and outcomes.png in ``out``."""
    make_folder(out)
    episodes = {"schema_version": SCHEMA_VERSION, "episodes": [r.to_json() for r in results]}
    (out / "episodes.json").write_text(json.dumps(episodes, indent=2) + "\n")
    names = sorted({k for r in results for k in r.metrics})
    # the localisation's errors, after the metrics, only in a bench that localised
    located = [k for k in LOCALIZATION_FIELDS if any(r.localization for r in results)]
    with open(out / "episodes.csv", "w", newline="") as fh:
        w = csv.writer(fh)
        head = ["schema_version", "seed", "status", "sim_time", "wall_time", "ticks",
                "failed_node", "reason"]
        w.writerow([*head, "injected", *names, *located])
        for r in results:
            row = [SCHEMA_VERSION, r.seed, r.status, f"{r.sim_time:.3f}", f"{r.wall_time:.3f}",
                   r.ticks]
            row += [r.failed_node, r.reason, len(r.injected)]
            loc = r.localization or {}
            w.writerow(row + [r.metrics.get(k, "") for k in names]
                       + [loc.get(k, "") for k in located])
    summary_json = {"schema_version": SCHEMA_VERSION, **asdict(summary)}
    if summary.localization is None:
        del summary_json["localization"]
    (out / "summary.json").write_text(json.dumps(summary_json, indent=2) + "\n")
    _plot(results, summary, out / "outcomes.png")


def _plot(results: list[EpisodeResult], summary: BenchSummary, path: Path) -> None:
    """Write :func:`outcomes_figure` to ``path`` (PNG)."""
    import matplotlib.pyplot as plt

    fig = outcomes_figure(results, summary)
    fig.savefig(path, dpi=90)
    plt.close(fig)


def outcomes_figure(results: list[EpisodeResult], summary: BenchSummary) -> Any:
    """The figure of outcomes.png: sim time per seed (left, coloured by outcome) and a
    histogram of the sim time per episode (right, stacked by outcome); integer ticks on the
    seed and count axes."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.ticker import MaxNLocator

    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(11, 4))
    statuses = [s for s in STATUS_COLOURS if any(r.status == s for r in results)]
    statuses += sorted({r.status for r in results} - set(statuses))
    colours = [STATUS_COLOURS.get(s, "black") for s in statuses]
    for status, colour in zip(statuses, colours, strict=True):
        pts = [(r.seed, r.sim_time) for r in results if r.status == status]
        xs, ys = zip(*pts, strict=True)
        ax1.scatter(xs, ys, c=colour, label=f"{status} ({len(pts)})", s=18)
    ax1.xaxis.set_major_locator(MaxNLocator(integer=True))
    ax1.set_xlabel("seed")
    ax1.set_ylabel("sim time (s)")
    lo, hi = summary.ci95
    ax1.set_title(
        f"success {summary.success_rate * 100:.1f} % (95 % CI {lo * 100:.0f}-{hi * 100:.0f} %)"
    )
    if statuses:
        ax1.legend(fontsize=8)
        ax2.hist(
            [[r.sim_time for r in results if r.status == s] for s in statuses],
            bins=min(20, max(5, len(results) // 2)),
            color=colours,
            stacked=True,
            label=statuses,
        )
    ax2.yaxis.set_major_locator(MaxNLocator(integer=True))
    ax2.set_xlabel("sim time per episode (s)")
    ax2.set_ylabel("episodes")
    ax2.set_title(f"histogram of sim time per episode ({summary.runs} episodes)")
    rtf = summary.real_time_factor["median"]
    fig.suptitle(
        f"{Path(summary.tree).name} on {Path(summary.world).name or 'no world'} "
        f"(median real-time factor {rtf:.1f}x)"
    )
    fig.tight_layout()
    return fig
