"""The reach of an arm is maximised once per chain: a second model of the same chain reuses it
(in this process, and from the cache folder in another), a different chain gets its own."""

from __future__ import annotations

from pathlib import Path

import pytest

from bt_manip.kinematics import ArmModel
from bt_manip.kinematics import arm_model as module
from bt_manip.sim.assets import ur3_urdf


@pytest.fixture
def counted(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> list[str]:
    """An empty reach memo and cache folder; returns the tips whose reach was maximised."""
    monkeypatch.setenv("BT_MANIP_IK_CACHE", str(tmp_path))
    monkeypatch.setattr(module, "_REACH_MEMO", {})
    calls: list[str] = []
    original = ArmModel._maximise_reach

    def maximise(self: ArmModel, starts: int = 16) -> float:
        calls.append(self.tip_link)
        return original(self, starts)

    monkeypatch.setattr(ArmModel, "_maximise_reach", maximise)
    return calls


def test_same_chain_reuses_the_reach_and_another_chain_gets_its_own(
    counted: list[str],
) -> None:
    first = ArmModel.from_urdf(ur3_urdf(), "base_link", "tool0").reach()
    second = ArmModel.from_urdf(ur3_urdf(), "base_link", "tool0").reach()
    shorter = ArmModel.from_urdf(ur3_urdf(), "base_link", "wrist_2_link").reach()
    assert counted == ["tool0", "wrist_2_link"]
    assert second == first
    assert 0.3 < shorter < first < 0.7  # the UR3 reaches about 0.5 m to its flange


def test_another_process_reads_the_stored_reach_and_ignores_a_broken_file(
    counted: list[str], monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    first = ArmModel.from_urdf(ur3_urdf(), "base_link", "tool0").reach()
    monkeypatch.setattr(module, "_REACH_MEMO", {})  # as in a fresh process
    assert ArmModel.from_urdf(ur3_urdf(), "base_link", "tool0").reach() == first
    assert counted == ["tool0"]
    (stored,) = (tmp_path / "reach").iterdir()
    stored.write_text("not a number\n")
    monkeypatch.setattr(module, "_REACH_MEMO", {})
    assert ArmModel.from_urdf(ur3_urdf(), "base_link", "tool0").reach() == first
    assert counted == ["tool0", "tool0"]
