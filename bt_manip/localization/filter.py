"""Monte Carlo localisation: a particle filter on a map, as Nav2's AMCL does it.

Use::

    field = LikelihoodField.from_grid(grid, options.laser_likelihood_max_dist)
    pf = ParticleFilter(field, options, np.random.default_rng(seed))
    pf.set_initial_pose((x, y, yaw), sigmas=(0.3, 0.3, 0.2))   # or pf.global_localization()
    for odom, scan in stream:
        if pf.update(odom, scan):                               # False: not moved enough yet
            est = pf.estimate                                    # pose, covariance, lost

Each update that is taken (the first one, then one per ``update_min_d`` of travel or
``update_min_a`` of turn since the last, by odometry):

1. moves every particle by a noisy copy of the odometry since the last update
   (:mod:`.motion_model`), so the map -> odom relation is carried by the particles;
2. weighs each by the likelihood field (:mod:`.likelihood_field`) with ``max_beams`` beams;
3. updates the slow and fast averages of the scan's likelihood (``recovery_alpha_slow``,
   ``recovery_alpha_fast``): each particle's geometric mean likelihood per beam, averaged with
   the new weights;
4. every ``resample_interval`` updates, resamples (:mod:`.resampling`) as many particles as the
   KLD bound asks for (:mod:`.kld`), each replaced with probability ``max(0, 1 - fast/slow)`` by
   a random pose in the free space (recovery from a kidnap).

The estimate (:mod:`.estimate`) and whether the filter is lost are worked out on the weighted
particles after step 3, before resampling adds its own noise.

All randomness comes from the generator passed in: the same seed and inputs give the same
particles, bit for bit.
"""

from __future__ import annotations

import math

import numpy as np

from bt_manip.localization import particles as pset
from bt_manip.localization.estimate import PoseEstimate, best_cluster
from bt_manip.localization.inputs import OdomPose, Scan
from bt_manip.localization.kld import bin_keys, kld_prefix, standard_normal_quantile
from bt_manip.localization.likelihood_field import LikelihoodField, SensorModel
from bt_manip.localization.motion_model import sample_motion, sample_motion_planar
from bt_manip.localization.options import LocalizationOptions, OptionsError
from bt_manip.localization.resampling import low_variance

__all__ = ["LocalizationOptions", "OptionsError", "ParticleFilter"]


class NotInitialised(RuntimeError):
    """An update came before an initial pose or a global localisation."""


class ParticleFilter:
    """Monte Carlo localisation of one base on one map (see the module's docstring)."""

    def __init__(
        self,
        field: LikelihoodField,
        options: LocalizationOptions | None = None,
        rng: np.random.Generator | None = None,
    ) -> None:
        options = options if options is not None else LocalizationOptions()
        if not isinstance(options, LocalizationOptions):
            raise TypeError("options must be LocalizationOptions")
        self.field = field
        self.options = options
        self.rng = rng if rng is not None else np.random.default_rng(0)
        self.sensor = SensorModel(field, options.z_hit, options.z_rand, options.sigma_hit)
        self._wide_sensor: SensorModel | None = None
        self._z = standard_normal_quantile(options.pf_z)
        self._set: pset.ParticleSet | None = None
        self._last_odom: tuple[float, float, float] | None = None
        self._w_slow = 0.0
        self._w_fast = 0.0
        self._updates = 0
        self._estimate: PoseEstimate | None = None
        self.weighed_wide = False
        """Whether the last scan taken was weighed with the wider field (see
        :meth:`_spread`)."""

    # -- starting ------------------------------------------------------------------------------
    def set_initial_pose(
        self,
        pose: tuple[float, float, float],
        sigmas: tuple[float, float, float] | None = None,
    ) -> None:
        """Start from ``pose`` (x, y, yaw in the map frame) with standard deviations ``sigmas``
        (x, y, yaw; the options' ``initial_sigma_*`` when not given), ``max_particles`` drawn
        around it."""
        o = self.options
        s = sigmas if sigmas is not None else (o.initial_sigma_xy, o.initial_sigma_xy,
                                                o.initial_sigma_yaw)
        if len(pose) != 3 or len(s) != 3 or not all(math.isfinite(v) for v in (*pose, *s)):
            raise ValueError(f"an initial pose and its sigmas are three finite numbers each, "
                             f"not {pose!r} and {s!r}")
        if any(v < 0 for v in s):
            raise ValueError(f"initial sigmas must be >= 0, not {s!r}")
        self._start(pset.gaussian(pose, s, o.max_particles, self.rng))

    def global_localization(self) -> None:
        """Start with ``max_particles`` spread uniformly over the map's free cells."""
        self._start(pset.uniform(self.field, self.options.max_particles, self.rng))

    def _start(self, poses: np.ndarray) -> None:
        self._set = pset.even(poses)
        self._last_odom = None  # the next update is taken whatever the travel
        self._w_slow = self._w_fast = 0.0
        self._estimate = self._estimate_of(self._set)

    # -- the update ----------------------------------------------------------------------------
    def update(self, odom: OdomPose, scan: Scan) -> bool:
        """Take ``scan`` at odometry pose ``odom`` if the base moved enough since the last
        update (or this is the first); True when it was taken."""
        if self._set is None:
            raise NotInitialised("give an initial pose (set_initial_pose) or call "
                                 "global_localization before the first update")
        o = self.options
        new = (odom.x, odom.y, odom.yaw)
        old = self._last_odom
        if old is not None:
            moved = math.hypot(new[0] - old[0], new[1] - old[1])
            turned = abs((new[2] - old[2] + math.pi) % (2.0 * math.pi) - math.pi)
            if moved < o.update_min_d and turned < o.update_min_a:
                return False
            model = sample_motion_planar if o.motion_model == "planar" else sample_motion
            poses = model(self._set.poses, old, new, (o.alpha1, o.alpha2, o.alpha3,
                                                              o.alpha4, o.alpha5), self.rng)
        else:
            poses = self._set.poses
        self._last_odom = new
        wide = self.weighed_wide = self._spread()
        sensor = self.wide_sensor if wide else self.sensor
        ends = sensor.beam_ends(scan, o.max_beams)
        logs = sensor.log_likelihoods(poses, ends, scan.range_max)
        t = logs * (min(o.beam_weight, o.beam_weight_wide) if wide else o.beam_weight)
        like = np.exp(t - t.max())
        w = self._set.weights * like
        total = float(w.sum())
        # the old weights and the new likelihoods may not overlap at all (a long while without
        # resampling): the scan alone decides then
        w = w / total if total > 0 else like / like.sum()
        if len(ends):
            # the scan's likelihood: each pose's per-beam geometric mean, averaged with the new
            # weights, so that it says how well the particles that count explain the scan (the
            # random particles of the last resampling, nearly all wrong, barely move it)
            self._average_likelihood(float(w @ np.exp(logs / len(ends))))
        current = pset.ParticleSet(poses, w)
        self._updates += 1
        # the weighted set, before resampling adds its own noise, gives the estimate
        self._estimate = self._estimate_of(current)
        if self._updates % o.resample_interval == 0:
            current = self._resample(current)
        self._set = current
        return True

    @property
    def wide_sensor(self) -> SensorModel:
        """The broader field used while the particles are spread (see :meth:`_spread`), made
        the first time it is needed (a filter that never loses the robot never makes it)."""
        if self._wide_sensor is None:
            o = self.options
            self._wide_sensor = SensorModel(self.field, o.z_hit, o.z_rand,
                                            max(o.sigma_hit, o.sigma_hit_wide))
        return self._wide_sensor

    def _spread(self) -> bool:
        """Whether the particles are spread over more than one place (the last estimate's
        cluster holds under ``lost_cluster_weight`` of the weight, or its position spread is
        over ``lost_std_xy``): after a global localisation, or while the filter is finding
        the robot again. The scan is then weighed with the wider field (``sigma_hit_wide``,
        ``beam_weight_wide``): with few particles near the true pose, the sharp field would
        let the best of the wrong places win before any particle lands in its narrow basin."""
        est = self._estimate
        if est is None:
            return False
        o = self.options
        sx, sy, _ = est.std
        return est.cluster_weight < o.lost_cluster_weight or max(sx, sy) > o.lost_std_xy

    def _average_likelihood(self, w_avg: float) -> None:
        """Update the slow and fast averages of the weighted mean likelihood (both start at
        the first value)."""
        o = self.options
        if self._w_slow == 0.0:
            self._w_slow = self._w_fast = w_avg
            return
        self._w_slow += o.recovery_alpha_slow * (w_avg - self._w_slow)
        self._w_fast += o.recovery_alpha_fast * (w_avg - self._w_fast)

    @property
    def random_share(self) -> float:
        """Share of the particles drawn at random at the next resampling."""
        o = self.options
        if o.recovery_alpha_slow <= 0 or o.recovery_alpha_fast <= 0 or self._w_slow <= 0:
            return 0.0
        return max(0.0, 1.0 - self._w_fast / self._w_slow)

    def _resample(self, ps: pset.ParticleSet) -> pset.ParticleSet:
        o = self.options
        m = o.max_particles
        picked = ps.poses[self.rng.permutation(low_variance(ps.weights, m, self.rng))]
        share = self.random_share
        if share > 0:
            fresh = self.rng.random(m) < share
            k = int(fresh.sum())
            if k:
                picked[fresh] = pset.uniform(self.field, k, self.rng)
        keys = bin_keys(picked, o.kld_bin_xy, o.kld_bin_yaw)
        n = kld_prefix(keys, o.pf_err, self._z, o.min_particles, o.max_particles)
        return pset.even(picked[:n].copy())

    # -- what it knows -------------------------------------------------------------------------
    @property
    def particles(self) -> pset.ParticleSet:
        """A copy of the current particles."""
        if self._set is None:
            raise NotInitialised("the filter has no particles yet")
        return pset.ParticleSet(self._set.poses.copy(), self._set.weights.copy())

    @property
    def estimate(self) -> PoseEstimate:
        """The current estimate (see :mod:`.estimate`)."""
        if self._estimate is None:
            raise NotInitialised("the filter has no estimate yet")
        return self._estimate

    @property
    def updates(self) -> int:
        """Scans taken so far."""
        return self._updates

    def _estimate_of(self, ps: pset.ParticleSet) -> PoseEstimate:
        o = self.options
        mean, cov, inside = best_cluster(ps, o.kld_bin_xy, o.kld_bin_yaw, o.cluster_radius,
                                         o.cluster_yaw)
        sx, sy, syaw = (math.sqrt(max(0.0, float(cov[i, i]))) for i in range(3))
        reason = ""
        share = float(ps.weights[inside].sum())
        if share < o.lost_cluster_weight:
            reason = (f"the best cluster holds {share:.0%} of the weight, under "
                      f"lost_cluster_weight {o.lost_cluster_weight:g}")
        elif max(sx, sy) > o.lost_std_xy:
            reason = (f"position spread {max(sx, sy):.2f} m exceeds lost_std_xy "
                      f"{o.lost_std_xy:g} m")
        elif syaw > o.lost_std_yaw:
            reason = f"heading spread {syaw:.2f} rad exceeds lost_std_yaw {o.lost_std_yaw:g} rad"
        elif self._w_slow > 0 and self._w_fast < o.lost_likelihood_ratio * self._w_slow:
            reason = (f"the scans' likelihood fell to {self._w_fast / self._w_slow:.0%} of its "
                      f"long-run average (lost_likelihood_ratio {o.lost_likelihood_ratio:g})")
        return PoseEstimate(
            float(mean[0]), float(mean[1]), float(mean[2]),
            _rows3(cov),
            share, len(ps), bool(reason), reason,
        )


def _rows3(m: np.ndarray) -> tuple[tuple[float, float, float], ...]:
    """A 3 x 3 array as a tuple of row tuples of floats."""
    return tuple((float(r[0]), float(r[1]), float(r[2])) for r in m)
