"""A weighted set of pose hypotheses and the ways to make one.

:class:`ParticleSet` holds ``poses`` (n, 3) as ``(x, y, yaw)`` rows in the map frame and
``weights`` (n,) summing to 1. :func:`gaussian` draws one around a pose (an initial pose with
its standard deviations); :func:`uniform` spreads one over free cells (global localisation and
the random particles of a recovery). All randomness comes from the ``numpy.random.Generator``
passed in.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Protocol

import numpy as np


@dataclass(frozen=True)
class ParticleSet:
    """Poses (n, 3) with weights (n,) that sum to 1."""

    poses: np.ndarray
    weights: np.ndarray

    def __len__(self) -> int:
        return int(self.poses.shape[0])


def even(poses: np.ndarray) -> ParticleSet:
    """``poses`` with equal weights."""
    n = poses.shape[0]
    return ParticleSet(poses, np.full(n, 1.0 / n))


def gaussian(
    pose: tuple[float, float, float],
    sigmas: tuple[float, float, float],
    n: int,
    rng: np.random.Generator,
) -> np.ndarray:
    """``n`` poses drawn around ``pose`` with standard deviations ``sigmas`` (x, y, yaw)."""
    out: np.ndarray = np.asarray(pose, dtype=float)[None, :] + rng.standard_normal(
        (n, 3)
    ) * np.asarray(sigmas, dtype=float)
    out[:, 2] = (out[:, 2] + math.pi) % (2.0 * math.pi) - math.pi
    return out


class FreeSpace(Protocol):
    """Where particles may be put: a number of free cells of side ``resolution`` and their
    centres (a :class:`~bt_manip.localization.likelihood_field.LikelihoodField` is one)."""

    @property
    def resolution(self) -> float: ...

    @property
    def free(self) -> np.ndarray: ...

    def free_points(self, picks: np.ndarray) -> np.ndarray: ...


def uniform(space: FreeSpace, n: int, rng: np.random.Generator) -> np.ndarray:
    """``n`` poses at uniformly random points of the free cells of ``space``, with uniformly
    random headings."""
    if space.free.size == 0:
        raise ValueError("the map has no free cell to put particles in")
    centres = space.free_points(rng.integers(0, space.free.size, n))
    jitter = (rng.random((n, 2)) - 0.5) * space.resolution
    out = np.empty((n, 3))
    out[:, :2] = centres + jitter
    out[:, 2] = rng.random(n) * (2.0 * math.pi) - math.pi
    return out
