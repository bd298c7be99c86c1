"""Shared test set-up: import bt_manip first so that pybullet loads quietly."""

import bt_manip  # noqa: F401
