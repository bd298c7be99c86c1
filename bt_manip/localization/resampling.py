"""Low-variance (systematic) resampling.

One random offset ``u`` in ``[0, 1/m)`` and the ``m`` evenly spaced pointers ``u + k/m`` pick
particles from the cumulative weights: a particle of weight ``w`` is picked ``floor(w m)`` or
``ceil(w m)`` times, never more or fewer, so the set's proportions survive resampling with the
least added noise (Thrun, Burgard and Fox, *Probabilistic Robotics*, table 4.4).
"""

from __future__ import annotations

import numpy as np


def low_variance(weights: np.ndarray, m: int, rng: np.random.Generator) -> np.ndarray:
    """Indices (m,) of the particles picked from ``weights`` (non-negative, not all 0), in
    order of the particles."""
    w = np.asarray(weights, dtype=float)
    if m < 1:
        raise ValueError(f"cannot draw {m} particles")
    total = float(w.sum())
    if w.ndim != 1 or w.size == 0 or not np.isfinite(total) or total <= 0 or (w < 0).any():
        raise ValueError("weights must be a non-empty array of non-negative numbers, not all 0")
    cdf = np.cumsum(w / total)
    pointers = (rng.random() + np.arange(m)) / m
    return np.minimum(np.searchsorted(cdf, pointers, side="right"), w.size - 1)
