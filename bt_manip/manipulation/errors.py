"""The error a manipulation helper raises when it cannot do what it is asked."""

from __future__ import annotations


class ManipulationError(Exception):
    """A manipulation helper cannot do what it is asked; the message says why, in the words
    a behaviour node reports as its FAILURE reason."""
