"""The ``bim`` extra of pyproject.toml installs what IfcOpenShell's API needs: writing a building
model with ``ifcopenshell.api`` (as tests/bim/ifc_buildings.py does) before ``bt-manip bim``
reads it prints no note of a missing dependency."""

from __future__ import annotations

import subprocess
import sys

import pytest

pytest.importorskip("ifcopenshell")


def test_ifcopenshells_whole_api_imports_without_a_missing_dependency_note() -> None:
    # the sequence API (task schedules) is the one part of it that needs networkx
    done = subprocess.run(
        [sys.executable, "-c", "import ifcopenshell.api, ifcopenshell.api.sequence"],
        capture_output=True, text=True, timeout=120, stdin=subprocess.DEVNULL,
    )
    assert done.returncode == 0, done.stderr
    assert "not available" not in done.stdout + done.stderr, done.stdout + done.stderr
