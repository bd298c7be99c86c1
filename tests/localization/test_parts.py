"""The filter's parts on their own: options, inputs, resampling, the KLD bound, the motion model,
the likelihood field and the estimate."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest
from loc_scene import room_grid

from bt_manip.localization import LikelihoodField, LocalizationOptions, OptionsError, Scan
from bt_manip.localization.estimate import best_cluster
from bt_manip.localization.inputs import OdomPose
from bt_manip.localization.kld import bin_keys, kld_bound, kld_prefix
from bt_manip.localization.motion_model import sample_motion, sample_motion_planar
from bt_manip.localization.particles import ParticleSet, even
from bt_manip.localization.resampling import low_variance


@pytest.mark.parametrize(
    ("changes", "words"),
    [
        ({"min_particles": -5}, "min_particles must be at least 1, not -5"),
        ({"max_particles": 0}, "max_particles must be at least 1"),
        ({"min_particles": 800, "max_particles": 400}, "min_particles (800) must not exceed"),
        ({"max_beams": 2.5}, "max_beams must be a whole number"),
        ({"pf_z": 1.0}, "pf_z must be between 0 and 1"),
        ({"pf_err": 0.0}, "pf_err must be > 0"),
        ({"alpha3": -0.1}, "alpha3 must be >= 0"),
        ({"sigma_hit": float("nan")}, "sigma_hit must be a finite number"),
        ({"z_hit": 0.0, "z_rand": 0.0}, "z_hit and z_rand must not both be 0"),
        ({"recovery_alpha_fast": 0.0005}, "recovery_alpha_fast (0.0005) must exceed"),
        ({"recovery_alpha_slow": 1.5}, "recovery_alpha_slow must be between 0 and 1"),
        ({"max_particles": 10**7}, "max_particles must be at most"),
        ({"motion_model": "omni"}, "motion_model must be one of diff, planar, not 'omni'"),
        ({"alpha5": -1.0}, "alpha5 must be >= 0"),
    ],
)
def test_bad_options_are_refused_by_name(changes: dict, words: str) -> None:
    with pytest.raises(OptionsError) as err:
        replace(LocalizationOptions(), **changes)
    assert words in str(err.value)


def test_recovery_can_be_turned_off_as_in_nav2() -> None:
    o = replace(LocalizationOptions(), recovery_alpha_slow=0.0, recovery_alpha_fast=0.0)
    assert o.recovery_alpha_fast == 0.0


def test_bad_inputs_are_refused_by_field() -> None:
    with pytest.raises(ValueError, match="ranges must be a non-empty 1-D array"):
        Scan(np.ones((2, 3)), 0.0, 0.1, 5.0)
    with pytest.raises(ValueError, match="range_max must be > 0"):
        Scan(np.ones(3), 0.0, 0.1, 0.0)
    with pytest.raises(ValueError, match="angle_increment must not be 0"):
        Scan(np.ones(3), 0.0, 0.0, 5.0)
    with pytest.raises(ValueError, match="sensor_pose must be three finite numbers"):
        Scan(np.ones(3), 0.0, 0.1, 5.0, sensor_pose=(0.0, 0.0))
    with pytest.raises(ValueError, match="more than the"):
        Scan(np.ones(200_000), 0.0, 1e-5, 5.0)
    with pytest.raises(ValueError, match="yaw must be a finite number"):
        OdomPose(0.0, 0.0, float("inf"))


def test_low_variance_resampling_keeps_the_proportions() -> None:
    rng = np.random.default_rng(0)
    idx = low_variance(np.array([0.5, 0.25, 0.125, 0.125]), 800, rng)
    assert np.bincount(idx, minlength=4).tolist() == [400, 200, 100, 100]
    w = rng.random(50)
    w /= w.sum()
    for _ in range(20):
        counts = np.bincount(low_variance(w, 1000, rng), minlength=50)
        assert counts.sum() == 1000
        assert np.all(counts >= np.floor(w * 1000) - 1e-9)
        assert np.all(counts <= np.ceil(w * 1000) + 1e-9)
    with pytest.raises(ValueError, match="not all 0"):
        low_variance(np.zeros(3), 5, rng)


def test_kld_bound_grows_with_the_bins_and_the_prefix_follows_it() -> None:
    b = kld_bound(np.arange(1, 200), 0.05, 2.326)
    assert b[0] == 1 and np.all(np.diff(b) > 0)
    same = np.zeros(5000, np.int64)
    assert kld_prefix(same, 0.05, 2.326, 100, 5000) == 5000  # one bin tells nothing: as AMCL
    two = np.r_[0, 1, np.zeros(4998, np.int64)]
    assert kld_prefix(two, 0.05, 2.326, 100, 5000) == 100  # two bins: the minimum
    distinct = np.arange(5000, dtype=np.int64)
    assert kld_prefix(distinct, 0.05, 2.326, 100, 5000) == 5000  # never enough: the maximum
    ten = np.tile(np.arange(10), 500)  # ten bins, filled at once
    n = kld_prefix(ten, 0.05, 2.326, 1, 5000)
    assert n == int(kld_bound(10, 0.05, 2.326))


def test_bins_split_x_y_and_yaw() -> None:
    poses = np.array([[0.1, 0.1, 0.0], [0.4, 0.4, 0.1], [0.6, 0.1, 0.0], [0.1, 0.1, 1.0]])
    keys = bin_keys(poses, 0.5, math.radians(10))
    assert keys[0] == keys[1] and len(set(keys.tolist())) == 3


def test_the_motion_model_without_noise_moves_each_particle_in_its_own_frame() -> None:
    rng = np.random.default_rng(0)
    poses = np.array([[1.0, 1.0, math.pi / 2], [0.0, 0.0, 0.0]])
    moved = sample_motion(poses, (0.0, 0.0, 0.0), (1.0, 0.0, 0.3), (0, 0, 0, 0), rng)
    assert moved[0] == pytest.approx([1.0, 2.0, math.pi / 2 + 0.3])
    assert moved[1] == pytest.approx([1.0, 0.0, 0.3])
    back = sample_motion(poses, (0.0, 0.0, 0.0), (-0.5, 0.0, 0.0), (0, 0, 0, 0), rng)
    assert back[0] == pytest.approx([1.0, 0.5, math.pi / 2])


def test_the_motion_model_spreads_as_the_alphas_say() -> None:
    rng = np.random.default_rng(1)
    poses = np.zeros((20000, 3))
    moved = sample_motion(poses, (0.0, 0.0, 0.0), (1.0, 0.0, 0.0), (0.0, 0.0, 0.04, 0.0), rng)
    # only alpha3: the travel's standard deviation is sqrt(0.04) x 1 m, along x only
    assert np.std(moved[:, 0]) == pytest.approx(0.2, rel=0.05)
    assert np.allclose(moved[:, 1:], 0.0)


def test_the_planar_model_without_noise_moves_each_particle_in_its_own_frame() -> None:
    rng = np.random.default_rng(0)
    poses = np.array([[1.0, 1.0, math.pi / 2], [0.0, 0.0, 0.0]])
    # from (0, 0, 0) to (0.3, 0.1, 0.4): 0.3 forward, 0.1 to the left, a 0.4 rad turn
    moved = sample_motion_planar(poses, (0.0, 0.0, 0.0), (0.3, 0.1, 0.4), (0,) * 5, rng)
    assert moved[0] == pytest.approx([0.9, 1.3, math.pi / 2 + 0.4])
    assert moved[1] == pytest.approx([0.3, 0.1, 0.4])
    # the same move seen from an odometry frame turned by 1 rad: the same in the base's frame
    c, s = math.cos(1.0), math.sin(1.0)
    again = sample_motion_planar(poses, (0.0, 0.0, 1.0), (0.3 * c - 0.1 * s, 0.3 * s + 0.1 * c,
                                                          1.4), (0,) * 5, rng)
    assert again == pytest.approx(moved)


def test_a_turn_on_the_spot_with_a_slide_scatters_the_diff_model_not_the_planar_one() -> None:
    """A skid-steer turning 0.2 rad slides 3 cm sideways: the diff model reads a 90 deg turn
    there and back, whose noise throws the particles metres away and turns them by half a
    radian; the planar model spreads them as a 0.2 rad turn alone would (alpha4: about 9 cm
    along the heading; alpha1: 0.09 rad)."""
    rng = np.random.default_rng(2)
    poses = np.zeros((20000, 3))
    alphas = (0.2, 0.2, 0.2, 0.2, 0.0)
    move = ((0.0, 0.0, 0.0), (0.0, -0.03, 0.2))
    diff = sample_motion(poses, *move, alphas, rng)
    planar = sample_motion_planar(poses, *move, alphas, rng)
    spread = lambda p: float(np.percentile(np.hypot(p[:, 0], p[:, 1] + 0.03), 95))  # noqa: E731
    assert spread(diff) > 1.0
    assert spread(planar) < 0.25
    assert float(np.std(diff[:, 2])) > 0.5
    assert float(np.std(planar[:, 2])) == pytest.approx(0.09, rel=0.05)
    # alpha5 spreads the planar model across the heading in proportion to the turn
    side = sample_motion_planar(poses, *move, (0.0, 0.0, 0.0, 0.0, 0.25), rng)
    across = -np.sin(side[:, 2]) * side[:, 0] + np.cos(side[:, 2]) * (side[:, 1] + 0.03)
    assert float(np.std(across)) == pytest.approx(0.5 * 0.2, rel=0.05)


def test_the_likelihood_field_is_the_distance_to_the_nearest_wall() -> None:
    grid = room_grid()
    field = LikelihoodField.from_grid(grid, max_dist=1.0)
    # the south wall fills y in [0, 0.1]; a point at y = 0.6 lies 0.5 m above it (cell centres)
    d = field.distance_at(np.array([2.0]), np.array([0.625]))
    assert d[0] == pytest.approx(0.5, abs=0.051)
    assert field.distance_at(np.array([2.0]), np.array([0.05]))[0] == 0.0
    assert field.distance_at(np.array([40.0]), np.array([0.0]))[0] == 1.0  # off the map
    far = field.distance_at(np.array([2.0]), np.array([1.9]))[0]
    assert far == 1.0  # capped
    assert len(field.free) == int((~grid.occupied).sum())
    centres = field.free_points(np.arange(len(field.free)))
    cells = np.array([grid.world_to_cell(x, y) for x, y in centres])
    assert not grid.occupied[cells[:, 0], cells[:, 1]].any()


def test_the_estimate_is_the_heaviest_cluster() -> None:
    rng = np.random.default_rng(2)
    a = np.array([1.0, 1.0, 0.5]) + 0.02 * rng.standard_normal((300, 3))
    b = np.array([5.0, 3.0, -2.0]) + 0.02 * rng.standard_normal((100, 3))
    ps = even(np.concatenate([a, b]))
    mean, cov, inside = best_cluster(ps, 0.5, math.radians(10), 0.5, 0.6)
    assert mean == pytest.approx([1.0, 1.0, 0.5], abs=0.01)
    assert inside[:300].all() and not inside[300:].any()
    assert math.sqrt(cov[0, 0]) == pytest.approx(0.02, rel=0.2)
    heavy_b = ParticleSet(ps.poses, np.r_[np.full(300, 0.1 / 300), np.full(100, 0.9 / 100)])
    mean_b, _, _ = best_cluster(heavy_b, 0.5, math.radians(10), 0.5, 0.6)
    assert mean_b == pytest.approx([5.0, 3.0, -2.0], abs=0.01)
