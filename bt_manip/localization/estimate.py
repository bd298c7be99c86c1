"""The pose a particle set stands for, how sure it is, and whether it is lost.

The estimate is the weighted mean of the best cluster: the heaviest histogram bin (the KLD
bins) is the seed, and a window of ``cluster_radius`` metres and ``cluster_yaw`` radians is
moved to the weighted mean of the particles inside it a few times (mean shift). When every
particle is in the window (a unimodal set), that is the mean of all particles. Headings are
averaged on the circle. The covariance and standard deviations are those of the cluster.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numba
import numpy as np

from bt_manip.localization.kld import bin_keys
from bt_manip.localization.particles import ParticleSet

MEAN_SHIFT_STEPS = 4
"""Most times the cluster window is moved to the mean of what it holds."""


@dataclass(frozen=True)
class PoseEstimate:
    """Where the filter thinks the base is (map frame) and how sure it is."""

    x: float
    y: float
    yaw: float
    covariance: tuple[tuple[float, float, float], ...]
    """3 x 3 covariance of (x, y, yaw) over the cluster."""
    cluster_weight: float
    """Share of the total weight in the cluster the estimate comes from."""
    particles: int
    lost: bool
    reason: str
    """Why the filter says it is lost ('' when it is not)."""

    @property
    def std(self) -> tuple[float, float, float]:
        """Standard deviations of x (m), y (m) and yaw (rad)."""
        c = self.covariance
        return (math.sqrt(c[0][0]), math.sqrt(c[1][1]), math.sqrt(c[2][2]))


@numba.njit(cache=True)
def _mean_shift(  # pragma: no cover - compiled
    poses: np.ndarray, w: np.ndarray, centre: np.ndarray, radius: float, half_yaw: float,
    steps: int, inside: np.ndarray,
) -> None:
    """Move ``centre`` (in place) to the weighted mean of the particles in its window up to
    ``steps`` times, stopping when the window no longer changes; ``inside`` (in place) marks
    the particles of the last window, all False if it held no weight."""
    n = poses.shape[0]
    r2 = radius * radius
    two_pi = 2.0 * np.pi
    for step in range(steps + 1):
        changed = False
        sw = sx = sy = sc = ss = 0.0
        for i in range(n):
            dx = poses[i, 0] - centre[0]
            dy = poses[i, 1] - centre[1]
            dyaw = (poses[i, 2] - centre[2] + np.pi) % two_pi - np.pi
            now = dx * dx + dy * dy <= r2 and abs(dyaw) <= half_yaw
            if now != inside[i]:
                changed = True
                inside[i] = now
            if now:
                sw += w[i]
                sx += w[i] * poses[i, 0]
                sy += w[i] * poses[i, 1]
                sc += w[i] * np.cos(poses[i, 2])
                ss += w[i] * np.sin(poses[i, 2])
        if sw <= 0.0:
            inside[:] = False
            return
        if step == steps or (step > 0 and not changed):
            return
        centre[0] = sx / sw
        centre[1] = sy / sw
        centre[2] = np.arctan2(ss, sc)


def _mean(poses: np.ndarray, w: np.ndarray) -> np.ndarray:
    w = w / w.sum()
    yaw = math.atan2(float(w @ np.sin(poses[:, 2])), float(w @ np.cos(poses[:, 2])))
    return np.array([float(w @ poses[:, 0]), float(w @ poses[:, 1]), yaw])


def best_cluster(
    ps: ParticleSet, bin_xy: float, bin_yaw: float, radius: float, half_yaw: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(mean pose (3,), covariance (3, 3), mask of the cluster's particles)``."""
    poses = np.ascontiguousarray(ps.poses, dtype=np.float64)
    w = np.ascontiguousarray(ps.weights, dtype=np.float64)
    keys = bin_keys(poses, bin_xy, bin_yaw)
    uniq, inverse = np.unique(keys, return_inverse=True)
    heaviest = int(np.argmax(np.bincount(inverse, weights=w, minlength=uniq.size)))
    seed = inverse == heaviest
    centre = _mean(poses[seed], w[seed]) if w[seed].sum() > 0 else _mean(poses, w + 1.0)
    inside = np.zeros(len(poses), np.bool_)
    _mean_shift(poses, w, centre, radius, half_yaw, MEAN_SHIFT_STEPS, inside)
    if not inside.any():
        inside[:] = True
        centre = _mean(poses, w) if w.sum() > 0 else _mean(poses, w + 1.0)
    else:
        centre = _mean(poses[inside], w[inside])
    wc = w[inside] / w[inside].sum()
    d = poses[inside] - centre[None, :]
    d[:, 2] = (d[:, 2] + math.pi) % (2.0 * math.pi) - math.pi
    cov = (d * wc[:, None]).T @ d
    return centre, cov, inside
