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


def _window(poses: np.ndarray, centre: np.ndarray, radius: float, half_yaw: float) -> np.ndarray:
    d = poses[:, :2] - centre[None, :2]
    dyaw = (poses[:, 2] - centre[2] + math.pi) % (2.0 * math.pi) - math.pi
    inside: np.ndarray = (np.einsum("ij,ij->i", d, d) <= radius * radius) & (
        np.abs(dyaw) <= half_yaw
    )
    return inside


def _mean(poses: np.ndarray, w: np.ndarray) -> np.ndarray:
    w = w / w.sum()
    yaw = math.atan2(float(w @ np.sin(poses[:, 2])), float(w @ np.cos(poses[:, 2])))
    return np.array([float(w @ poses[:, 0]), float(w @ poses[:, 1]), yaw])


def best_cluster(
    ps: ParticleSet, bin_xy: float, bin_yaw: float, radius: float, half_yaw: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(mean pose (3,), covariance (3, 3), mask of the cluster's particles)``."""
    poses, w = ps.poses, ps.weights
    keys = bin_keys(poses, bin_xy, bin_yaw)
    uniq, inverse = np.unique(keys, return_inverse=True)
    heaviest = int(np.argmax(np.bincount(inverse, weights=w, minlength=uniq.size)))
    inside = inverse == heaviest
    centre = _mean(poses[inside], w[inside])
    for _ in range(MEAN_SHIFT_STEPS):
        window = _window(poses, centre, radius, half_yaw)
        if np.array_equal(window, inside):
            break  # the window holds what the mean came from: it would not move
        inside = window
        if not inside.any() or w[inside].sum() <= 0:
            break
        centre = _mean(poses[inside], w[inside])
    if not inside.any() or w[inside].sum() <= 0:
        inside = np.ones(len(ps), bool)
        centre = _mean(poses, w)
    wc = w[inside] / w[inside].sum()
    d = poses[inside] - centre[None, :]
    d[:, 2] = (d[:, 2] + math.pi) % (2.0 * math.pi) - math.pi
    cov = (d * wc[:, None]).T @ d
    return centre, cov, inside
