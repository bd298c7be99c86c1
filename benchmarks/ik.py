"""IK benchmark: bt-manip's CasADi solver side by side with TRAC-IK, same process, same poses.

The protocol of the TRAC-IK authors: N random joint vectors within the limits -> forward
kinematics -> solve from the mid-limits seed; success when the pose error is at most 1e-5 on
every axis (position in m, rotation vector in rad). Both solvers' answers are checked with
Pinocchio's forward kinematics under that same criterion, and both get a 5 ms time-out.

Prints one JSON line per arm and solver (success %, mean / median / p99 / max time in ms, plus
for context how often an answer came back at all and how many answers are within 1e-4), then
one summary line per arm with the ratios against TRAC-IK. TRAC-IK runs two solvers in two
threads per call, so on a busy machine its times suffer more than single-threaded ones.

    .venv/bin/python benchmarks/ik.py --n 10000
    .venv/bin/python benchmarks/ik.py --n 2000 --arms ur3

Needs the ``bench`` extra (``pytracik``). The Sawyer row needs ``robots/sawyer.urdf``.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from bt_manip.cli.args import positive
from bt_manip.kinematics import ArmModel, IKOptions, IKSolver
from bt_manip.sim.assets import REPO_ROOT, ur3_urdf

TOLERANCE = 1e-5
TIMEOUT = 0.005


@dataclass
class ArmCase:
    name: str
    urdf: Path
    base: str
    tip: str


def cases() -> dict[str, ArmCase]:
    return {
        "ur3": ArmCase("ur3", ur3_urdf(), "base_link", "tool0"),
        "sawyer": ArmCase("sawyer", REPO_ROOT / "robots" / "sawyer.urdf", "right_arm_base_link",
                          "right_hand"),
    }


def pose_error(arm: ArmModel, q: np.ndarray, target: np.ndarray) -> float:
    """Largest per-axis error: position (m) and rotation vector of R_target R^T (rad)."""
    import pinocchio as pin

    pose = arm.fk(q)
    dp = np.abs(target[:3, 3] - pose[:3, 3]).max()
    dr = np.abs(pin.log3(target[:3, :3] @ pose[:3, :3].T)).max()
    return float(max(dp, dr))


def stats(name: str, solver: str, times: list[float], errors: list[float], extra: dict) -> dict:
    t = np.array(times) * 1e3
    err = np.array(errors)
    return {
        "arm": name,
        "solver": solver,
        "n": len(times),
        "success_pct": round(100.0 * float(np.mean(err <= TOLERANCE)), 3),
        # Context: how often the solver returned an answer at all, and how many of the
        # answers miss 1e-5 but are within 1e-4 on every axis.
        "returned_pct": round(100.0 * float(np.mean(np.isfinite(err))), 3),
        "within_1e-4_pct": round(100.0 * float(np.mean(err <= 1e-4)), 3),
        "mean_ms": round(float(t.mean()), 4),
        "median_ms": round(float(np.median(t)), 4),
        "p99_ms": round(float(np.percentile(t, 99)), 4),
        "max_ms": round(float(t.max()), 3),
        **extra,
    }


def run_arm(case: ArmCase, n: int, seed: int) -> list[dict]:
    from trac_ik import TracIK

    arm = ArmModel.from_urdf(case.urdf, case.base, case.tip)
    ours = IKSolver(arm, IKOptions(time_budget=TIMEOUT))
    trac = TracIK(case.base, case.tip, str(case.urdf), timeout=TIMEOUT, epsilon=TOLERANCE)
    if trac.dof != arm.nq:
        raise SystemExit(f"{case.name}: TRAC-IK sees {trac.dof} joints, bt-manip {arm.nq}")
    rng = np.random.default_rng(seed)
    seed_q = arm.mid.copy()

    def run_ours(target: np.ndarray) -> np.ndarray | None:
        res = ours.solve(target, seed_q)
        return res.q if res.success else None

    def run_trac(target: np.ndarray) -> np.ndarray | None:
        return trac.ik(target[:3, 3], target[:3, :3], seed_q)

    solvers: dict[str, Callable[[np.ndarray], np.ndarray | None]] = {
        "bt-manip": run_ours,
        "trac-ik": run_trac,
    }
    times: dict[str, list[float]] = {k: [] for k in solvers}
    errors: dict[str, list[float]] = {k: [] for k in solvers}  # inf: no answer
    outside: dict[str, int] = dict.fromkeys(solvers, 0)
    # Warm-up (first calls pay for lazy initialisation), not counted.
    warm = arm.fk(arm.random_configuration(np.random.default_rng(seed + 1)))
    for fn in solvers.values():
        fn(warm)
    order = list(solvers)
    for i in range(n):
        target = arm.fk(arm.random_configuration(rng))
        # Alternate who goes first so both see the same machine load.
        for name in order if i % 2 == 0 else reversed(order):
            t0 = time.perf_counter()
            q = solvers[name](target)
            times[name].append(time.perf_counter() - t0)
            error = math.inf if q is None else pose_error(arm, np.asarray(q), target)
            if q is not None and not arm.within_limits(np.asarray(q), slack=1e-6):
                outside[name] += 1
                error = math.inf
            errors[name].append(error)
    rows = [
        stats(case.name, name, times[name], errors[name], {"outside_limits": outside[name]})
        for name in solvers
    ]
    ours_row, trac_row = rows
    rows.append(
        {
            "arm": case.name,
            "summary": True,
            "success_ge_tracik": ours_row["success_pct"] >= trac_row["success_pct"],
            "mean_time_ratio": round(ours_row["mean_ms"] / trac_row["mean_ms"], 3),
            "mean_within_2x": ours_row["mean_ms"] <= 2.0 * trac_row["mean_ms"],
            "compiled": ours.compiled,
            "loadavg_1min": round(os.getloadavg()[0], 2),
        }
    )
    return rows


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=positive(int), default=10_000,
                        help="poses per arm (default 10000)")
    parser.add_argument("--seed", type=int, default=0, help="seed of the random poses")
    parser.add_argument("--arms", nargs="+", default=["ur3", "sawyer"], choices=["ur3", "sawyer"])
    args = parser.parse_args(argv)
    available = cases()
    for name in args.arms:
        case = available[name]
        if not case.urdf.is_file():
            print(json.dumps({"arm": name, "skipped": f"{case.urdf} not found"}), flush=True)
            continue
        for row in run_arm(case, args.n, args.seed):
            print(json.dumps(row), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
