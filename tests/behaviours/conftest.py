"""Fixtures of the behaviour tests (helpers live in bhelpers.py)."""

from bhelpers import house_at_pregrasp, table  # noqa: F401
