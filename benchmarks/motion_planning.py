"""Arm motion planning on MotionBenchMaker's Panda problems: bt-manip's RRT-Connect side by side
with RoboPlan 0.7.0 (RRT-Connect) and OMPL 2.0.1 (RRTConnect), in one run.

Every problem (7 families x 100; ``--per-family N`` takes the first N of each) is planned by
each planner with a wall-clock limit per problem (``--time-limit``), every planner checking
segments at the same step (``--step``, 0.05 rad), each followed by its own shortcutting
(bt-manip's shortcut, RoboPlan's PathShortcutter, OMPL's PathSimplifier). Every path is then
checked by one validator, bt-manip's :func:`~bt_manip.manipulation.motion_bench.validate_path`
on the exact collision meshes at 0.01 rad per joint along every segment: a path counts as valid
only if it passes.

- bt-manip: :func:`~bt_manip.manipulation.motion_bench.run_problem`, what ``bt-manip
  motion-bench`` runs (planning time = search + shortcutting + its own 0.01 rad re-check).
- OMPL: the ``ompl`` wheel (cp311) installed with ``--no-deps`` into
  ``benchmarks/.venv-peers/ompl-inprocess`` and imported in this process; its state validity
  checker is bt-manip's planning scene (a Python callback: OMPL's planner, bt-manip's collision
  checks); the validity checking resolution is ``step`` over the space's maximum extent (OMPL
  measures it in Euclidean joint distance, so no joint moves more than ``step`` between checks).
- RoboPlan: its own scene (URDF, SRDF, the primitives), C++ collision checks, installed in its
  own venv ``benchmarks/.venv-peers`` (it pins ``pin < 4.2``) and run there in a subprocess by
  ``motion_planning_roboplan.py``, one per family.

A peer that cannot be installed is reported and left out. Writes ``results.json`` (every
problem, every planner) and ``times.png`` (the planning-time distributions per family) to
``--out``, and prints one JSON line per planner and family plus a table.

    .venv/bin/python benchmarks/motion_planning.py --per-family 20
    .venv/bin/python benchmarks/motion_planning.py --time-limit 2 --out out/motion_planning
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from types import ModuleType
from typing import Any

import numpy as np

from bt_manip.cli.args import positive
from bt_manip.manipulation.mbm import family_problems, read_problem
from bt_manip.manipulation.mbm_data import fetch_mbm
from bt_manip.manipulation.motion_bench import (
    VALIDATE_STEP,
    BenchOptions,
    load_robot,
    run_problem,
    scene_for,
    setup_problem,
    validate_path,
)
from bt_manip.manipulation.rrt_connect import path_length

HERE = Path(__file__).resolve().parent
PEERS = HERE / ".venv-peers"
ROBOPLAN = "roboplan==0.7.0"
OMPL = "ompl==2.0.1"
PLANNERS = ("bt-manip", "ompl", "roboplan")


# -- installing the peers ----------------------------------------------------------------------
def _pip(python: Path | str, *args: str) -> tuple[bool, str]:
    done = subprocess.run([str(python), "-m", "pip", "-q", *args], capture_output=True,
                          text=True, check=False)
    lines = [ln for ln in (done.stderr + done.stdout).splitlines()
             if ln.strip() and not ln.startswith("WARNING: Location")]
    return done.returncode == 0, (lines[-1] if lines else "")


def roboplan_python() -> tuple[Path | None, str]:
    """The peers' venv interpreter with RoboPlan in it (made and filled when missing)."""
    python = PEERS / "bin" / "python"
    probe = [str(python), "-c", "import roboplan.rrt, roboplan.core"]
    if python.exists() and subprocess.run(probe, capture_output=True, check=False).returncode == 0:
        return python, ""
    if not python.exists():
        made = subprocess.run([sys.executable, "-m", "venv", str(PEERS)], capture_output=True,
                              text=True, check=False)
        if made.returncode != 0:
            return None, f"python -m venv {PEERS}: {made.stderr.strip()[-300:]}"
    ok, message = _pip(python, "install", ROBOPLAN)
    if not ok or subprocess.run(probe, capture_output=True, check=False).returncode != 0:
        return None, f"pip install {ROBOPLAN} into {PEERS}: {message or 'import fails'}"
    return python, ""


def import_ompl() -> tuple[ModuleType | None, str]:
    """OMPL's Python package, installed without dependencies beside the peers' venv."""
    target = PEERS / "ompl-inprocess"
    if not (target / "ompl").is_dir():
        ok, message = _pip(sys.executable, "install", "--no-deps", "--target", str(target), OMPL)
        if not ok:
            return None, f"pip install --target {target} {OMPL}: {message}"
    sys.path.insert(0, str(target))
    try:
        import ompl.base
        import ompl.geometric
        import ompl.util
    except ImportError as exc:
        return None, f"import ompl: {exc}"
    ompl.util.setLogLevel(ompl.util.LogLevel.LOG_ERROR)
    return ompl, ""


# -- the planners ------------------------------------------------------------------------------
def plan_ompl(ompl: Any, scene: Any, setup: Any, time_limit: float, step: float) -> dict:
    """OMPL's RRTConnect and PathSimplifier on bt-manip's planning scene."""
    ob, og = ompl.base, ompl.geometric
    n = len(setup.joints)
    space = ob.RealVectorStateSpace(n)
    bounds = ob.RealVectorBounds(n)
    for k in range(n):
        bounds.setLow(k, float(scene.lower[k]))
        bounds.setHigh(k, float(scene.upper[k]))
    space.setBounds(bounds)
    ss = og.SimpleSetup(space)

    def valid(state: Any) -> bool:
        return not scene.collides(np.fromiter((state[i] for i in range(n)), float, n))

    ss.setStateValidityChecker(valid)
    si = ss.getSpaceInformation()
    si.setStateValidityCheckingResolution(step / space.getMaximumExtent())
    ss.setPlanner(og.RRTConnect(si))
    start, goal = space.allocState(), space.allocState()
    for k in range(n):
        start[k] = float(setup.start[k])
        goal[k] = float(setup.goal[k])
    ss.setStartAndGoalStates(start, goal)
    ss.setup()
    began = time.perf_counter()
    ss.solve(time_limit)
    planned = time.perf_counter()
    if not ss.haveExactSolutionPath():
        return {"solved": False, "plan_ms": None, "shortcut_ms": None, "path": None,
                "error": "no exact solution"}
    ss.simplifySolution()
    done = time.perf_counter()
    path = [[float(s[i]) for i in range(n)] for s in ss.getSolutionPath().getStates()]
    return {"solved": True, "plan_ms": (planned - began) * 1e3,
            "shortcut_ms": (done - planned) * 1e3, "path": path, "error": ""}


def run_roboplan(python: Path, robot: Any, group: str, joints: tuple[str, ...],
                 problems: list[dict], options: BenchOptions) -> list[dict]:
    job = {"urdf": str(robot.urdf), "srdf": str(robot.srdf) if robot.srdf else "",
           "group": group, "joints": list(joints), "step": options.step,
           "time_limit_s": options.time_limit_s, "seed": options.seed, "problems": problems}
    with tempfile.TemporaryDirectory() as tmp:
        job_file, out_file = Path(tmp) / "job.json", Path(tmp) / "out.json"
        job_file.write_text(json.dumps(job))
        done = subprocess.run([str(python), str(HERE / "motion_planning_roboplan.py"),
                               str(job_file), str(out_file)], capture_output=True, text=True,
                              check=False)
        if done.returncode != 0 or not out_file.exists():
            tail = done.stderr.strip()[-400:]
            return [{"id": p["id"], "solved": False, "plan_ms": None, "shortcut_ms": None,
                     "path": None, "error": f"worker failed: {tail}"} for p in problems]
        return list(json.loads(out_file.read_text()))


def first_contact(exact: Any, path: list[np.ndarray]) -> str:
    """Where an invalid path first touches, checked as the validator does: the segment, how
    far along it (rad of the largest joint move) and the pairs in contact."""
    for i in range(len(path) - 1):
        a, b = path[i], path[i + 1]
        n = max(1, int(np.ceil(float(np.max(np.abs(b - a))) / VALIDATE_STEP)))
        for k in range(n + 1):
            q = a + (b - a) * (k / n)
            if exact.collides(q):
                pairs = ", ".join(f"{x}-{y}" for x, y in exact.contacts(q)[:3])
                return f"touches on segment {i} at {k}/{n}: {pairs}"
    return "leaves the joint limits or misses the start or goal"


# -- figures -----------------------------------------------------------------------------------
def stats(values: list[float]) -> dict[str, float | None]:
    if not values:
        return {"median": None, "mean": None, "p95": None}
    a = np.asarray(values, dtype=float)
    return {"median": round(float(np.median(a)), 3), "mean": round(float(a.mean()), 3),
            "p95": round(float(np.percentile(a, 95)), 3)}


def summarise(rows: list[dict], planner: str, family: str) -> dict:
    mine = [r for r in rows if r["planner"] == planner and family in ("overall", r["family"])]
    solved = [r for r in mine if r["solved"]]
    return {
        "planner": planner, "family": family, "problems": len(mine), "solved": len(solved),
        "valid": sum(r["valid"] for r in mine),
        "time_ms": stats([r["planning_ms"] for r in solved]),
        "search_ms": stats([r["search_ms"] for r in solved if r["search_ms"] is not None]),
        "path_length_rad": stats([r["path_length_rad"] for r in solved]),
    }


def plot(rows: list[dict], families: list[str], planners: list[str], png: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(12, 5))
    width = 0.8 / max(1, len(planners))
    colours = {"bt-manip": "tab:blue", "ompl": "tab:orange", "roboplan": "tab:green"}
    for k, planner in enumerate(planners):
        data = [[r["planning_ms"] for r in rows if r["planner"] == planner
                 and r["family"] == f and r["solved"]] or [float("nan")] for f in families]
        positions = [i + (k - (len(planners) - 1) / 2) * width for i in range(len(families))]
        parts = ax.boxplot(data, positions=positions, widths=width * 0.9, patch_artist=True,
                           showfliers=True, flierprops={"markersize": 2},
                           medianprops={"color": "black"})
        for box in parts["boxes"]:
            box.set_facecolor(colours.get(planner, "grey"))
        ax.plot([], [], "s", color=colours.get(planner, "grey"), label=planner)
    ax.set_xticks(range(len(families)))
    ax.set_xticklabels([f.removesuffix("_panda") for f in families], rotation=20)
    ax.set_yscale("log")
    ax.set_ylabel("planning time per solved problem (ms, with shortcutting)")
    ax.set_title("MotionBenchMaker Panda: planning time per family")
    ax.legend()
    fig.tight_layout()
    fig.savefig(png, dpi=110)


# -- the run -----------------------------------------------------------------------------------
def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--per-family", type=positive(int), default=None,
                        help="first N problems of each")
    parser.add_argument("--families", default="", help="comma-separated family folder names")
    parser.add_argument("--time-limit", type=positive(float), default=1.0,
                        help="seconds per problem")
    parser.add_argument("--step", type=positive(float), default=0.05, help="collision step (rad)")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--planners", default=",".join(PLANNERS))
    parser.add_argument("--data", default=None, help="an unpacked resources/panda folder with "
                        "problems/ (default: fetched into bt-manip's cache)")
    parser.add_argument("--out", default="out/motion_planning")
    args = parser.parse_args()

    if args.data:
        root = Path(args.data)
        urdf, srdf, problems_dir = root / "panda.urdf", root / "panda.srdf", root / "problems"
    else:
        data = fetch_mbm("panda")
        urdf, srdf, problems_dir = data.urdf, data.srdf, data.problems
    families = sorted(p.name for p in problems_dir.iterdir() if p.is_dir())
    if args.families:
        families = [f for f in families if f in args.families.split(",")]
    robot = load_robot(urdf, srdf)
    options = BenchOptions(time_limit_s=args.time_limit, seed=args.seed, step=args.step)
    wanted = [p for p in args.planners.split(",") if p]
    planners = []
    ompl = roboplan = None
    for name in wanted:
        if name == "bt-manip":
            planners.append(name)
        elif name == "ompl":
            ompl, why = import_ompl()
            if ompl is None:
                print(json.dumps({"peer": "ompl", "left_out": why}), flush=True)
            else:
                planners.append(name)
        elif name == "roboplan":
            roboplan, why = roboplan_python()
            if roboplan is None:
                print(json.dumps({"peer": "roboplan", "left_out": why}), flush=True)
            else:
                planners.append(name)
    rows: list[dict] = []
    began = time.perf_counter()
    for family in families:
        pairs = family_problems(problems_dir / family)[: args.per_family]
        peer_jobs: list[dict] = []
        checks: dict[str, Callable[[list[list[float]] | None],
                                   tuple[bool, float | None, str]]] = {}
        group_joints: tuple[str, ...] = ()
        group = ""
        for scene_file, request_file in pairs:
            problem = read_problem(scene_file, request_file)
            setup = setup_problem(robot, problem)
            group, group_joints = problem.group, setup.joints
            exact = scene_for(robot, setup, problem, exact=True)
            key = f"{family}/{scene_file.name}"

            def check(path: list[list[float]] | None, exact: Any = exact,
                      setup: Any = setup) -> tuple[bool, float | None, str]:
                if path is None:
                    return False, None, ""
                q = [np.asarray(p, dtype=float) for p in path]
                valid = validate_path(exact, q, setup.start, setup.goal)
                return valid, path_length(q), "" if valid else first_contact(exact, q)

            checks[key] = check
            if "bt-manip" in planners:
                o = run_problem(robot, scene_file, request_file, options)
                contact = "" if o.valid or o.path is None else check(o.path)[2]
                rows.append({"planner": "bt-manip", "family": family, "scene": scene_file.name,
                             "solved": o.solved, "valid": o.valid, "planning_ms": o.planning_ms,
                             "search_ms": None, "path_length_rad": o.path_length_rad,
                             "error": contact or o.reason})
            if ompl is not None:
                scene = scene_for(robot, setup, problem)
                r = plan_ompl(ompl, scene, setup, args.time_limit, args.step)
                valid, length, contact = check(r["path"])
                rows.append({"planner": "ompl", "family": family, "scene": scene_file.name,
                             "solved": r["solved"], "valid": valid,
                             "planning_ms": _total(r), "search_ms": r["plan_ms"],
                             "path_length_rad": length, "error": r["error"] or contact})
            peer_jobs.append({
                "id": key, "start": setup.start.tolist(), "goal": setup.goal.tolist(),
                "locked": setup.locked,
                "obstacles": [{"name": ob.name, "shape": ob.shape, "size": list(ob.size),
                               "pose": [list(r) for r in ob.pose]} for ob in problem.obstacles],
            })
        if roboplan is not None and peer_jobs:
            for r in run_roboplan(roboplan, robot, group, group_joints, peer_jobs, options):
                valid, length, contact = checks[r["id"]](r["path"])
                rows.append({"planner": "roboplan", "family": family,
                             "scene": r["id"].split("/", 1)[1], "solved": r["solved"],
                             "valid": valid, "planning_ms": _total(r), "search_ms": r["plan_ms"],
                             "path_length_rad": length, "error": r["error"] or contact})
        for planner in planners:
            print(json.dumps(summarise(rows, planner, family)), flush=True)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    summary = [summarise(rows, p, f) for f in [*families, "overall"] for p in planners]
    load = os.getloadavg()
    (out / "results.json").write_text(json.dumps({
        "time_limit_s": args.time_limit, "step_rad": args.step, "seed": args.seed,
        "per_family": args.per_family, "load_average": load, "cpus": os.cpu_count(),
        "wall_s": round(time.perf_counter() - began, 1), "summary": summary, "problems": rows,
    }, indent=1))
    plot(rows, families, planners, out / "times.png")
    print(f"\n{'family':<24} {'planner':<9} {'solved':>8} {'valid':>6} {'median':>9} "
          f"{'mean':>9} {'p95':>9} {'search med':>10} {'length med':>10}")
    for s in summary:
        t, search, length = s["time_ms"], s["search_ms"], s["path_length_rad"]
        print(f"{s['family']:<24} {s['planner']:<9} {s['solved']:>4}/{s['problems']:<3} "
              f"{s['valid']:>6} {_ms(t['median'])} {_ms(t['mean'])} {_ms(t['p95'])} "
              f"{_ms(search['median'], 10)} {_ms(length['median'], 10)}")
    print(f"wrote {out / 'results.json'} and {out / 'times.png'}; load average "
          f"{load[0]:.1f} {load[1]:.1f} {load[2]:.1f} on {os.cpu_count()} CPUs")
    sys.stdout.flush()
    os._exit(0)  # OMPL's bindings report their objects as leaked at interpreter exit


def _total(r: dict) -> float | None:
    return None if r["plan_ms"] is None else r["plan_ms"] + (r["shortcut_ms"] or 0.0)


def _ms(value: float | None, width: int = 9) -> str:
    return f"{'-':>{width}}" if value is None else f"{value:>{width}.1f}"


if __name__ == "__main__":
    raise SystemExit(main())
