"""Monte Carlo localisation side by side: bt-manip's particle filter and PyPI ``amcl`` 0.1.2
(Nav2's AMCL in C++ behind Python bindings: its beam model, as that package
builds it), on the same route, scans and odometry, in one run.

Run: ``.venv/bin/python benchmarks/localization.py [--seeds 5] [--particles 500]``

``amcl`` is GPLv3, so it is never a dependency of bt-manip: the script installs it itself
(``pip install --no-deps --target benchmarks/.venv-peers/amcl-inprocess amcl==0.1.2``) and
imports it in this process. Without it (no network, no wheel for this Python) only bt-manip's
line is printed, with the reason.

The map is ``worlds/tb3_house.yaml``'s static geometry (walls and furniture) as bt-manip's 5 cm
occupancy grid; both filters get that grid. The route runs ~11 m through free space, from the
corridor through the workshop and the wide doorway into the living room and on to the kitchen,
at 0.5 m/s with turns on the spot at 1 rad/s, a scan and an odometry reading every 0.1 s:

- scans (:func:`exact_scan`): 360 beams over a full turn from the true pose, cast exactly on the
  outlines of the same walls and furniture (box edges and circles), range_max 12 m, plus 1 cm
  Gaussian noise. The scan source is a function of the pose: a simulated LiDAR can replace it.
- odometry: each step's travel and turn scaled by ``1 + 0.05 N(0, 1)`` (5 % noise), summed.

Both filters start from the true pose with standard deviations 0.1 m, 0.1 m, 0.1 rad, use 500
particles at most (``--particles``), 60 beams, Nav2's alpha1..4 = 0.2, update every 0.25 m or
0.2 rad of odometry; each is given every reading and decides itself, or (amcl, which updates
on every call) is called only when the same travel thresholds are passed. After each update the
estimate is compared with the true pose. One JSON line per filter: mean / p95 / max position
error (cm), mean yaw error (deg), ms per update (wall time: median and mean; CPU time of the
process: mean), updates, seeds.
"""

from __future__ import annotations

import argparse
import itertools
import json
import math
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path
from types import ModuleType
from typing import Any

import numpy as np

from bt_manip.cli.args import positive
from bt_manip.localization import (
    LikelihoodField,
    LocalizationOptions,
    OdomPose,
    ParticleFilter,
    Scan,
    map_from_world,
    static_outlines,
)
from bt_manip.navigation.grid import OccupancyGrid
from bt_manip.navigation.shapes import Disc
from bt_manip.sim.world import World

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
PEER_DIR = HERE / ".venv-peers" / "amcl-inprocess"
AMCL = "amcl==0.1.2"

BEAMS = 360
RANGE_MAX = 12.0
RANGE_NOISE = 0.01
ODOM_NOISE = 0.05
SPEED = 0.5
TURN_RATE = 1.0
DT = 0.1
INITIAL_SIGMAS = (0.1, 0.1, 0.1)
ROUTE = [(-1.0, 3.0), (-0.5, 2.3), (-0.5, 0.0), (0.8, -0.4), (3.5, -0.4), (4.5, 0.3),
         (4.5, 2.2), (5.5, 2.4)]
"""Waypoints (m) of the route in the house: corridor, workshop, living room, kitchen."""


# -- the world's geometry and an exact scanner -------------------------------------------------
class ExactCaster:
    """Ranges along rays to the nearest of a set of segments and circles (exact, in numpy)."""

    def __init__(self, segments: np.ndarray, circles: np.ndarray) -> None:
        self.a = segments[:, 0, :]  # (s, 2)
        self.e = segments[:, 1, :] - segments[:, 0, :]
        self.circles = circles  # (c, 3): cx, cy, r

    @classmethod
    def of_world(cls, world: World) -> ExactCaster:
        segs: list[np.ndarray] = []
        circles: list[tuple[float, float, float]] = []
        for o in static_outlines(world):
            if isinstance(o, Disc):
                circles.append((o.cx, o.cy, o.radius))
            else:
                v = o.vertices
                segs += [np.array([v[i], v[(i + 1) % len(v)]]) for i in range(len(v))]
        return cls(np.array(segs), np.array(circles).reshape(-1, 3))

    def cast(self, ox: float, oy: float, angles: np.ndarray, range_max: float) -> np.ndarray:
        """Range (m) along each angle from (ox, oy); ``range_max`` where nothing is nearer."""
        d = np.column_stack([np.cos(angles), np.sin(angles)])  # (n, 2)
        best = np.full(angles.size, range_max)
        # ray o + t d against segment a + u e: solve with 2-D cross products
        ao = self.a - np.array([ox, oy])  # (s, 2)
        den = d[:, None, 0] * self.e[None, :, 1] - d[:, None, 1] * self.e[None, :, 0]
        with np.errstate(divide="ignore", invalid="ignore"):
            t = (ao[None, :, 0] * self.e[None, :, 1] - ao[None, :, 1] * self.e[None, :, 0]) / den
            u = (ao[None, :, 0] * d[:, None, 1] - ao[None, :, 1] * d[:, None, 0]) / den
        ok = (np.abs(den) > 1e-12) & (t > 0) & (u >= 0) & (u <= 1)
        best = np.minimum(best, np.where(ok, t, np.inf).min(axis=1, initial=range_max))
        if len(self.circles):
            oc = np.array([ox, oy])[None, :] - self.circles[:, :2]  # (c, 2)
            b = d @ oc.T  # (n, c)
            cterm = np.einsum("ij,ij->i", oc, oc) - self.circles[:, 2] ** 2
            disc = b * b - cterm[None, :]
            with np.errstate(invalid="ignore"):
                tc = -b - np.sqrt(disc)
            okc = (disc >= 0) & (tc > 0)
            best = np.minimum(best, np.where(okc, tc, np.inf).min(axis=1, initial=range_max))
        return best


def exact_scan(caster: ExactCaster, rng: np.random.Generator) -> Callable[[np.ndarray], Scan]:
    """A scan source: the true pose (x, y, yaw) -> a 360-beam scan with 1 cm noise."""
    rel = -math.pi + np.arange(BEAMS) * (2.0 * math.pi / BEAMS)

    def scan(pose: np.ndarray) -> Scan:
        r = caster.cast(float(pose[0]), float(pose[1]), pose[2] + rel, RANGE_MAX)
        hit = r < RANGE_MAX
        r = np.where(hit, r + RANGE_NOISE * rng.standard_normal(BEAMS), RANGE_MAX)
        return Scan(r, -math.pi, 2.0 * math.pi / BEAMS, RANGE_MAX)

    return scan


# -- the route ---------------------------------------------------------------------------------
def route_poses() -> np.ndarray:
    """True poses (k, 3) every DT along ROUTE: drive straight, turn on the spot at corners."""
    out: list[tuple[float, float, float]] = []
    x, y = ROUTE[0]
    yaw = math.atan2(ROUTE[1][1] - y, ROUTE[1][0] - x)
    out.append((x, y, yaw))
    for (ax, ay), (bx, by) in itertools.pairwise(ROUTE):
        goal = math.atan2(by - ay, bx - ax)
        turn = (goal - yaw + math.pi) % (2 * math.pi) - math.pi
        for _ in range(int(abs(turn) / (TURN_RATE * DT))):
            yaw += math.copysign(TURN_RATE * DT, turn)
            out.append((x, y, yaw))
        yaw = goal
        length = math.hypot(bx - ax, by - ay)
        steps = max(1, round(length / (SPEED * DT)))
        for k in range(1, steps + 1):
            out.append((ax + (bx - ax) * k / steps, ay + (by - ay) * k / steps, yaw))
        x, y = bx, by
    return np.array(out)


def noisy_odometry(truth: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Odometry poses (k, 3): each step's travel and turn (in the base frame) scaled by
    ``1 + ODOM_NOISE N(0, 1)`` and summed from the first true pose."""
    odom = np.empty_like(truth)
    odom[0] = truth[0]
    for k in range(1, len(truth)):
        a, b = truth[k - 1], truth[k]
        c, s = math.cos(a[2]), math.sin(a[2])
        fx, fy = c * (b[0] - a[0]) + s * (b[1] - a[1]), -s * (b[0] - a[0]) + c * (b[1] - a[1])
        dyaw = (b[2] - a[2] + math.pi) % (2 * math.pi) - math.pi
        gain = 1.0 + ODOM_NOISE * rng.standard_normal(2)
        fx, fy, dyaw = fx * gain[0], fy * gain[0], dyaw * gain[1]
        o = odom[k - 1]
        c, s = math.cos(o[2]), math.sin(o[2])
        odom[k] = (o[0] + c * fx - s * fy, o[1] + s * fx + c * fy, o[2] + dyaw)
    return odom


# -- the filters -------------------------------------------------------------------------------
class Ours:
    name = "bt-manip"

    def __init__(self, grid: OccupancyGrid, particles: int, seed: int) -> None:
        opts = LocalizationOptions(min_particles=min(500, particles), max_particles=particles)
        self.pf = ParticleFilter(LikelihoodField.from_grid(grid, opts.laser_likelihood_max_dist),
                                 opts, np.random.default_rng(seed))

    def start(self, pose: np.ndarray) -> None:
        self.pf.set_initial_pose(tuple(pose), INITIAL_SIGMAS)

    def step(self, odom: np.ndarray, scan: Scan, t: float) -> tuple[float, float, float] | None:
        if not self.pf.update(OdomPose(*map(float, odom), time=t), scan):
            return None
        e = self.pf.estimate
        return e.x, e.y, e.yaw


class Peer:
    name = "amcl 0.1.2"

    def __init__(self, amcl: ModuleType, grid: OccupancyGrid, particles: int) -> None:
        self.amcl = amcl
        mp = amcl.MotionParameters(0.2, 0.2, 0.2, 0.2, 0.2)
        # Nav2's defaults for the likelihood field: z_hit 0.5, z_rand 0.5, sigma_hit 0.2
        lp = amcl.LaserParameters(0.5, 0.05, 0.05, 0.5, 0.2, 0.1, 0.05, 60)
        self.loc = amcl.AMCL(min(500, particles), particles, 0.0, 0.0, mp, lp, "differential")
        rows = np.where(grid.occupied, 100, 0).astype(int)
        # amcl's grid is a list of rows (y), each of cells (x), placed by its lower-left corner;
        # the laser pose is set after the map (setting a map makes a new laser model)
        self.loc.set_map(amcl.create_occupancy_grid_from_list(
            rows.tolist(), grid.resolution, grid.origin[0], grid.origin[1]))
        self.loc.set_laser_pose(amcl.Vector3D(0.0, 0.0, 0.0))
        self.last: np.ndarray | None = None

    def start(self, pose: np.ndarray) -> None:
        cov = self.amcl.create_diagonal_covariance(*(s * s for s in INITIAL_SIGMAS))
        self.loc.set_initial_pose(self.amcl.Vector3D(*map(float, pose)), cov)
        self.last = None

    def step(self, odom: np.ndarray, scan: Scan, t: float) -> tuple[float, float, float] | None:
        if self.last is not None:
            moved = math.hypot(odom[0] - self.last[0], odom[1] - self.last[1])
            turned = abs((odom[2] - self.last[2] + math.pi) % (2 * math.pi) - math.pi)
            if moved < 0.25 and turned < 0.2:
                return None
        self.last = odom.copy()
        pairs = np.column_stack([scan.ranges, scan.angles]).tolist()
        laser = self.amcl.create_laser_scan_from_list(pairs, scan.range_max)
        self.loc.update(laser, self.amcl.Vector3D(*map(float, odom)))
        p = self.loc.get_pose_mean()
        return p.x, p.y, p.theta


def import_amcl() -> tuple[ModuleType | None, str]:
    """PyPI amcl, installed without dependencies beside the peers' venv when missing."""
    if not (PEER_DIR / "amcl").is_dir():
        done = subprocess.run(
            [sys.executable, "-m", "pip", "-q", "install", "--no-deps", "--target",
             str(PEER_DIR), AMCL], capture_output=True, text=True, check=False)
        if done.returncode != 0:
            lines = [ln for ln in (done.stderr + done.stdout).splitlines() if ln.strip()]
            return None, f"pip install {AMCL}: {lines[-1] if lines else 'failed'}"
    sys.path.insert(0, str(PEER_DIR))
    try:
        import amcl
    except ImportError as exc:
        return None, f"import amcl: {exc}"
    return amcl, ""


# -- the run -----------------------------------------------------------------------------------
def run(filters: list[Any], truth: np.ndarray, odom: np.ndarray,
        scan_of: Callable[[np.ndarray], Scan]) -> dict[str, dict[str, list[float]]]:
    """Feed both filters the same readings; errors and update times per filter."""
    out = {f.name: {"pos": [], "yaw": [], "ms": [], "cpu_ms": []} for f in filters}
    for f in filters:
        f.start(truth[0])
    for k in range(len(truth)):
        scan = scan_of(truth[k])
        for f in filters:
            began, cpu = time.perf_counter(), time.process_time()
            est = f.step(odom[k], scan, k * DT)
            ms = (time.perf_counter() - began) * 1e3
            cpu_ms = (time.process_time() - cpu) * 1e3
            if est is None:
                continue
            rec = out[f.name]
            rec["ms"].append(ms)
            rec["cpu_ms"].append(cpu_ms)
            rec["pos"].append(math.hypot(est[0] - truth[k, 0], est[1] - truth[k, 1]))
            rec["yaw"].append(abs((est[2] - truth[k, 2] + math.pi) % (2 * math.pi) - math.pi))
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=positive(int), default=5,
                    help="runs (odometry, scan, filter seeds)")
    ap.add_argument("--particles", type=positive(int), default=500,
                    help="most particles per filter")
    ap.add_argument("--no-peer", action="store_true", help="bt-manip only")
    args = ap.parse_args(argv)
    if not 1 <= args.seeds <= 100 or not 1 <= args.particles <= 100_000:
        print("--seeds must be 1..100 and --particles 1..100000", file=sys.stderr)
        return 2
    amcl, why = (None, "--no-peer") if args.no_peer else import_amcl()
    with World(ROOT / "worlds" / "tb3_house.yaml") as world:
        grid = map_from_world(world)
        caster = ExactCaster.of_world(world)
    truth = route_poses()
    # warm-up: compiled kernels and caches, outside the figures
    warm = np.random.default_rng(999)
    run([Ours(grid, args.particles, 999)], truth[:40], noisy_odometry(truth[:40], warm),
        exact_scan(caster, warm))
    totals: dict[str, dict[str, list[float]]] = {}
    for seed in range(args.seeds):
        rng = np.random.default_rng(1000 + seed)
        odom = noisy_odometry(truth, rng)
        filters: list[Any] = [Ours(grid, args.particles, seed)]
        if amcl is not None:
            filters.append(Peer(amcl, grid, args.particles))
        for name, rec in run(filters, truth, odom, exact_scan(caster, rng)).items():
            t = totals.setdefault(name, {"pos": [], "yaw": [], "ms": [], "cpu_ms": []})
            for key in t:
                t[key] += rec[key]
    length = float(np.sum(np.hypot(*np.diff(truth[:, :2], axis=0).T)))
    for name, t in totals.items():
        pos, ms = np.array(t["pos"]), np.array(t["ms"])
        print(json.dumps({
            "filter": name, "particles": args.particles, "route_m": round(length, 2),
            "seeds": args.seeds, "updates": int(pos.size),
            "mean_cm": round(100 * float(pos.mean()), 2),
            "p95_cm": round(100 * float(np.percentile(pos, 95)), 2),
            "max_cm": round(100 * float(pos.max()), 2),
            "mean_yaw_deg": round(math.degrees(float(np.mean(t["yaw"]))), 3),
            "ms_per_update_median": round(float(np.median(ms)), 3),
            "ms_per_update_mean": round(float(ms.mean()), 3),
            "cpu_ms_per_update_mean": round(float(np.mean(t["cpu_ms"])), 3),
        }))
    if amcl is None:
        print(json.dumps({"filter": "amcl 0.1.2", "skipped": why}))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
