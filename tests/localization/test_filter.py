"""The particle filter on a synthetic room with exact scans and 5 % odometry noise: tracking
from a wrong initial pose, global localisation, recovery from a kidnap, the KLD count, the
travel thresholds and determinism per seed."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import replace

import numpy as np
import pytest
from loc_scene import ROUTE, drive, odometry, pose_error, readings, room_grid

from bt_manip.localization import (
    LikelihoodField,
    LocalizationOptions,
    NotInitialised,
    OdomPose,
    ParticleFilter,
    Scan,
)

GRID = room_grid()
FIELD = LikelihoodField.from_grid(GRID)


def make(options: LocalizationOptions | None = None, seed: int = 0) -> ParticleFilter:
    return ParticleFilter(FIELD, options, np.random.default_rng(seed))


def track(pf: ParticleFilter, truth: np.ndarray, seed: int,
          shift: tuple[int, np.ndarray] | None = None,
          after_update: Callable[[], None] | None = None) -> list[tuple[int, float, float, bool]]:
    """Feed ``pf`` the route's readings; after each update taken, (step, position error, yaw
    error, lost), and ``after_update()`` called. ``shift`` = (step, offset): from that step on
    the robot really is at truth + offset, which odometry never hears of (a kidnap)."""
    rng = np.random.default_rng(100 + seed)
    odom = odometry(truth, rng)
    seen = truth.copy()
    if shift is not None:
        k0, off = shift
        seen[k0:] = truth[k0:] + off
    out = []
    for k, o, scan in readings(seen, odom, rng):
        if pf.update(o, scan):
            e = pf.estimate
            if after_update is not None:
                after_update()
            out.append((k, *pose_error((e.x, e.y, e.yaw), seen[k]), e.lost))
    return out


@pytest.mark.parametrize("seed", [0, 1])
def test_converges_from_a_wrong_initial_pose(seed: int) -> None:
    truth = drive(ROUTE)
    pf = make(seed=seed)
    start = truth[0] + np.array([0.3, -0.25, 0.15])  # wrong, but within the given sigmas
    pf.set_initial_pose(tuple(start), (0.4, 0.4, 0.3))
    errors = track(pf, truth, seed)
    assert len(errors) >= 30
    late = errors[10:]
    assert max(pos for _, pos, _, _ in late) < 0.05
    assert max(yaw for _, _, yaw, _ in late) < math.radians(3)
    assert not any(lost for *_, lost in late)


def test_global_localisation_finds_the_robot() -> None:
    truth = drive(ROUTE)
    pf = make(replace(LocalizationOptions(), max_particles=6000), seed=3)
    pf.global_localization()
    assert pf.estimate.lost  # spread over the whole room
    wide: list[bool] = []
    errors = track(pf, truth, 3, after_update=lambda: wide.append(pf.weighed_wide))
    _, pos, yaw, lost = errors[-1]
    assert pos < 0.05 and yaw < math.radians(3) and not lost
    # the spread particles were weighed with the wide field, the found robot with the sharp one
    assert wide[0] and not wide[-1]
    # found well before the end of the route, and kept from then on
    assert all(e[1] < 0.1 for e in errors[len(errors) // 2:])


def test_kld_count_falls_as_the_filter_converges() -> None:
    options = replace(LocalizationOptions(), min_particles=300, max_particles=6000)
    pf = make(options, seed=3)
    pf.global_localization()
    counts = [len(pf.particles)]
    truth = drive(ROUTE)
    rng = np.random.default_rng(103)
    for _, o, scan in readings(truth, odometry(truth, rng), rng):
        if pf.update(o, scan):
            counts.append(len(pf.particles))
    assert counts[0] == 6000  # spread out: as many as allowed
    assert counts[-1] < 1000  # converged: few bins, few particles
    assert min(counts) >= 300


def test_recovers_from_a_kidnap() -> None:
    # the robot drives to (4, 3) heading east, is carried 1 m south and turned 0.4 rad without
    # odometry knowing, and drives on from there
    before = drive(ROUTE[:4])
    turn = 0.4
    after = drive([(4.0, 2.0), (5.4, 2.0 + 1.4 * math.tan(turn)), (5.5, 1.2), (4.0, 1.2),
                   (4.0, 2.8), (2.2, 2.8), (2.2, 1.0), (1.0, 1.0)])
    truth = np.concatenate([before, after])
    k0 = len(before)
    rng = np.random.default_rng(105)
    odom = odometry(truth, rng, unseen=k0)
    pf = make(seed=5)
    pf.set_initial_pose(tuple(truth[0]), (0.1, 0.1, 0.1))
    errors = []
    for k, o, scan in readings(truth, odom, rng):
        if pf.update(o, scan):
            e = pf.estimate
            errors.append((k, *pose_error((e.x, e.y, e.yaw), truth[k]), e.lost))
    tracked = [e for e in errors if e[0] < k0]
    kidnapped = [e for e in errors if e[0] >= k0]
    assert tracked[-1][1] < 0.05
    assert kidnapped[0][1] > 0.5  # the kidnap is real
    assert any(e[3] for e in kidnapped[:15])  # and the filter says it is lost
    recovered = next(i for i, e in enumerate(kidnapped) if e[1] < 0.1 and e[2] < 0.1)
    assert recovered <= 30  # updates
    assert all(e[1] < 0.1 for e in kidnapped[recovered + 5:])
    assert not kidnapped[-1][3]


def test_same_seed_same_particles_other_seed_other_particles() -> None:
    truth = drive(ROUTE)[:40]

    def run(seed: int) -> np.ndarray:
        pf = make(seed=seed)
        pf.set_initial_pose(tuple(truth[0]), (0.3, 0.3, 0.2))
        track(pf, truth, 0)
        return pf.particles.poses

    a, b, c = run(7), run(7), run(8)
    assert np.array_equal(a, b)
    assert a.shape != c.shape or not np.array_equal(a, c)


def test_updates_only_after_enough_travel_or_turn() -> None:
    pf = make(seed=0)
    pf.set_initial_pose((1.0, 1.0, 0.0), (0.05, 0.05, 0.05))
    truth = np.array([1.0, 1.0, 0.0])
    from loc_scene import scan_at, segments

    scan = scan_at(truth, np.random.default_rng(0), segments())
    assert pf.update(OdomPose(0.0, 0.0, 0.0), scan)  # the first is always taken
    before = pf.particles.poses
    assert not pf.update(OdomPose(0.2, 0.0, 0.0), scan)  # 0.2 m < update_min_d
    assert not pf.update(OdomPose(0.1, 0.1, 0.15), scan)  # 0.14 m, 0.15 rad
    assert np.array_equal(pf.particles.poses, before)
    assert pf.updates == 1
    assert pf.update(OdomPose(0.0, 0.0, 0.25), scan)  # 0.25 rad >= update_min_a
    assert pf.update(OdomPose(0.3, 0.0, 0.25), scan)  # 0.3 m >= update_min_d
    assert pf.updates == 3


def test_an_update_before_a_start_is_refused() -> None:
    pf = make()
    scan = Scan(np.ones(10), 0.0, 0.1, 5.0)
    with pytest.raises(NotInitialised, match="initial pose"):
        pf.update(OdomPose(0.0, 0.0, 0.0), scan)
