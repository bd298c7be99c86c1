"""Where bt-manip keeps files it builds once and reuses (composed URDFs, compiled IK code)."""

from __future__ import annotations

import os
from pathlib import Path


def cache_dir(kind: str, override: str) -> Path:
    """``$<override>`` if set, else ``$XDG_CACHE_HOME/bt-manip/<kind>`` (``~/.cache`` by
    default). The folder is not created here."""
    env = os.environ.get(override)
    if env:
        return Path(env)
    xdg = os.environ.get("XDG_CACHE_HOME")
    root = Path(xdg) if xdg else Path.home() / ".cache"
    return root / "bt-manip" / kind
