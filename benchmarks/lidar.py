"""The simulated laser's ray caster side by side with PyBullet's rayTestBatch, in one run.

Run: ``.venv/bin/python benchmarks/lidar.py [--poses 50] [--repeat 5] [--threads 1]``

``worlds/tb3_house.yaml`` with the Husky and its declared ``front_laser`` (270 deg, 541 beams,
12 m, noise off). The Husky is put at ``--poses`` seeded free poses of the house (each reached
by ``reset_base_pose``, checked free of overlap); at each, bt-manip's scan (the whole
``Lidar.scan()``: sensor pose, the scene brought up to date, the cast) and PyBullet's
``rayTestBatch`` along the same beams (``--threads`` of its own; 1 by default) are timed in
turns, ``--repeat`` times each, after one warm-up call. One JSON line per caster (median time
per scan over all poses and repeats), then one line comparing their ranges: the fraction of
beams within 1 mm, the median and largest difference, and the same over the beams a fair
comparison keeps (neither grazing a face, under 15 degrees, nor at the edge of a body).
"""

from __future__ import annotations

import argparse
import json
import math
import statistics
import time

import numpy as np
import pybullet as pb

from bt_manip.cli.args import positive
from bt_manip.sensing.lidar import Lidar
from bt_manip.sim import pybullet_queries as pbq
from bt_manip.sim.world import World


def free_poses(world: World, n: int, seed: int) -> list[tuple[float, float, float]]:
    """``n`` poses of the Husky inside the house touching nothing (seeded)."""
    robot = world.robots["husky"]
    rng = np.random.default_rng(seed)
    others = [i.body_id for i in world.infos.values() if i.kind not in ("ground", "robot")]
    poses: list[tuple[float, float, float]] = []
    while len(poses) < n:
        pose = (float(rng.uniform(-7.0, 7.0)), float(rng.uniform(-4.5, 4.5)),
                float(rng.uniform(-math.pi, math.pi)))
        robot.reset_base_pose(*pose)
        if all(not pbq.closest_points(world.client, robot.body, b, 0.02) for b in others):
            poses.append(pose)
    return poses


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--poses", type=positive(int), default=50)
    parser.add_argument("--repeat", type=positive(int), default=5)
    parser.add_argument("--threads", type=positive(int), default=1)
    parser.add_argument("--seed", type=int, default=1)
    args = parser.parse_args()
    world = World("worlds/tb3_house.yaml")
    robot = world.robots["husky"]
    lidar = Lidar(world, robot)
    ours: list[float] = []
    theirs: list[float] = []
    diffs: list[np.ndarray] = []
    fair: list[np.ndarray] = []
    for pose in free_poses(world, args.poses, args.seed):
        robot.reset_base_pose(*pose)
        origin, heading = lidar.sensor_pose()
        scan = lidar.scan()  # warm-up (and the scene brought up to date)
        angles = heading + scan.angles
        starts = [origin.tolist()] * len(angles)
        ends = (origin + scan.range_max * np.column_stack(
            [np.cos(angles), np.sin(angles), np.zeros(len(angles))])).tolist()
        hits = pb.rayTestBatch(starts, ends, numThreads=args.threads,
                               physicsClientId=world.client)
        for _ in range(args.repeat):
            t = time.perf_counter()
            scan = lidar.scan()
            ours.append(time.perf_counter() - t)
            t = time.perf_counter()
            hits = pb.rayTestBatch(starts, ends, numThreads=args.threads,
                                   physicsClientId=world.client)
            theirs.append(time.perf_counter() - t)
        ref = np.array([h[2] * scan.range_max if h[0] >= 0 else scan.range_max for h in hits])
        diff = np.abs(scan.ranges - ref)
        keep = np.ones(len(hits), dtype=bool)
        for k, h in enumerate(hits):
            if h[0] >= 0:
                keep[k] = abs(h[4][0] * math.cos(angles[k]) + h[4][1] * math.sin(angles[k])) \
                    > math.sin(math.radians(15.0))
            for j in (k - 1, k + 1):
                if 0 <= j < len(hits) and hits[j][:2] != h[:2]:
                    keep[k] = False
        diffs.append(diff)
        fair.append(diff[keep])
    world.close()
    ms_ours, ms_theirs = statistics.median(ours) * 1e3, statistics.median(theirs) * 1e3
    beams = len(diffs[0])
    print(json.dumps({"caster": "bt-manip Lidar.scan", "beams": beams, "poses": args.poses,
                      "median_ms": round(ms_ours, 4),
                      "time_vs_raytestbatch": round(ms_ours / ms_theirs, 4)}))
    print(json.dumps({"caster": "pybullet rayTestBatch", "threads": args.threads,
                      "beams": beams, "poses": args.poses, "median_ms": round(ms_theirs, 4)}))
    every, kept = np.concatenate(diffs), np.concatenate(fair)
    print(json.dumps({
        "ranges": "bt-manip vs rayTestBatch",
        "within_1mm": round(float((every < 1e-3).mean()), 5),
        "median_mm": round(float(np.median(every)) * 1e3, 5),
        "max_mm": round(float(every.max()) * 1e3, 3),
        "kept_fraction": round(len(kept) / len(every), 4),
        "kept_within_1mm": round(float((kept < 1e-3).mean()), 5),
        "kept_max_mm": round(float(kept.max()) * 1e3, 3),
    }))


if __name__ == "__main__":
    main()
