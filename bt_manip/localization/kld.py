"""KLD sampling: how many particles a set needs, from how many histogram bins it covers.

Fox's bound (*Adapting the sample size in particle filters through KLD-sampling*, 2003): with
``k`` occupied bins, ``n = (k - 1) / (2 err) * (1 - 2/(9(k-1)) + sqrt(2/(9(k-1))) z)^3``
particles keep the divergence between the set and the true posterior under ``err`` (``pf_err``)
with probability given by the standard normal quantile ``z`` (``pf_z``). A filter sure of its
pose fills few bins and needs few particles; a spread-out one needs many.

:func:`kld_prefix` applies it as AMCL does while it draws particles one at a time: it returns
the shortest prefix of a drawn sequence that is as long as the bound for the bins that prefix
fills (bounded by ``min_particles`` and ``max_particles``), all at once with numpy.
"""

from __future__ import annotations

import math
from statistics import NormalDist

import numpy as np


def standard_normal_quantile(p: float) -> float:
    """``z`` with P(Z <= z) = ``p`` for a standard normal Z."""
    return NormalDist().inv_cdf(p)


def kld_bound(k: np.ndarray | int, err: float, z: float) -> np.ndarray:
    """Particles needed for ``k`` occupied bins (1 for k <= 1; :func:`kld_prefix` asks for the
    maximum then)."""
    kk = np.asarray(k, dtype=float)
    km1 = np.maximum(kk - 1.0, 1.0)
    a = 2.0 / (9.0 * km1)
    n = km1 / (2.0 * err) * (1.0 - a + np.sqrt(a) * z) ** 3
    return np.where(kk <= 1.0, 1.0, np.ceil(n))


def bin_keys(poses: np.ndarray, bin_xy: float, bin_yaw: float) -> np.ndarray:
    """One integer per pose naming its histogram bin (x, y, yaw)."""
    ix = np.floor(poses[:, 0] / bin_xy).astype(np.int64)
    iy = np.floor(poses[:, 1] / bin_xy).astype(np.int64)
    nyaw = max(1, math.ceil(2.0 * math.pi / bin_yaw))
    iyaw = np.floor((poses[:, 2] + math.pi) / bin_yaw).astype(np.int64) % nyaw
    span = 1 << 24  # cells of 1 cm give +-80 km before two bins share a key
    return ((ix + span // 2) * span + (iy + span // 2)) * nyaw + iyaw


def kld_prefix(
    keys: np.ndarray, err: float, z: float, min_particles: int, max_particles: int
) -> int:
    """Length of the shortest prefix of ``keys`` (bins in drawing order) that holds at least as
    many particles as the KLD bound for the bins it fills, within ``[min_particles,
    max_particles]`` (and at most ``len(keys)``)."""
    m = min(len(keys), max_particles)
    if m <= min_particles:
        return m
    keys = keys[:m]
    _, first = np.unique(keys, return_index=True)
    new_bin = np.zeros(m, np.int64)
    new_bin[first] = 1
    filled = np.cumsum(new_bin)  # bins filled by the first 1, 2, ... particles
    # one bin says nothing about the spread: as AMCL, draw on until a second bin is filled
    need = np.where(filled <= 1, max_particles, np.maximum(kld_bound(filled, err, z),
                                                            min_particles))
    enough = np.nonzero(np.arange(1, m + 1) >= need)[0]
    return int(enough[0]) + 1 if enough.size else m
