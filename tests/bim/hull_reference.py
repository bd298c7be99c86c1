"""Reference hulls the footprint tests compare bt-manip's with: Andrew's monotone chain as
textbooks write it, with numpy's extent for its rounding tolerance."""

from __future__ import annotations

import numpy as np


def textbook_chain(pts: np.ndarray) -> np.ndarray:
    """The hull's corners (counter-clockwise) of distinct points sorted by x then y."""
    eps = 1e-15 * float(np.abs(pts).max()) * float(np.ptp(pts, axis=0).max())

    def half(points: list[list[float]]) -> list[list[float]]:
        out: list[list[float]] = []
        for p in points:
            while len(out) >= 2 and ((out[-1][0] - out[-2][0]) * (p[1] - out[-2][1])
                                     - (out[-1][1] - out[-2][1]) * (p[0] - out[-2][0])) <= eps:
                out.pop()
            out.append(p)
        return out

    rows = pts.tolist()
    return np.array(half(rows)[:-1] + half(rows[::-1])[:-1], dtype=float).reshape(-1, 2)
