"""A converted world loaded with many seeds: every randomised start must be free
(``bt-manip bim --seed-range``)."""

from __future__ import annotations

from pathlib import Path

from bt_manip.errors import InputError
from bt_manip.sim.world import World


def check_seeds(world_path: Path, seeds: range) -> None:
    """Load the world with each seed (PyBullet): the randomised starts must not overlap."""
    problems = []
    for seed in seeds:
        try:
            with World(world_path, seed=seed):
                pass
        except InputError as exc:
            problems += [
                type(p)(p.file, p.line, f"seed {seed}: {p.message}", p.column) for p in exc.problems
            ]
    if problems:
        raise InputError(problems)
