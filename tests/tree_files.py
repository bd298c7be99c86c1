"""Test helper: tree files written for the command-line tests."""

from __future__ import annotations

from pathlib import Path


def write_tree(tmp_path: Path, body: str, name: str = "t.xml") -> Path:
    """A BT.CPP v4 file ``name`` in ``tmp_path`` whose main tree ``Main`` holds ``body``."""
    path = tmp_path / name
    path.write_text(
        '<root BTCPP_format="4" main_tree_to_execute="Main">\n'
        f'  <BehaviorTree ID="Main">\n{body}\n  </BehaviorTree>\n</root>\n'
    )
    return path
