"""The reach of an arm is maximised once per process and chain: a second model of the same
chain reuses it, a different chain gets its own."""

from __future__ import annotations

import pytest

from bt_manip.kinematics import ArmModel
from bt_manip.kinematics import arm_model as module
from bt_manip.sim.assets import ur3_urdf


def test_same_chain_reuses_the_reach_and_another_chain_gets_its_own(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.setattr(module, "_REACH_MEMO", {})
    calls: list[str] = []
    original = ArmModel._maximise_reach

    def counted(self: ArmModel, starts: int = 16) -> float:
        calls.append(self.tip_link)
        return original(self, starts)

    monkeypatch.setattr(ArmModel, "_maximise_reach", counted)
    first = ArmModel.from_urdf(ur3_urdf(), "base_link", "tool0").reach()
    second = ArmModel.from_urdf(ur3_urdf(), "base_link", "tool0").reach()
    shorter = ArmModel.from_urdf(ur3_urdf(), "base_link", "wrist_2_link").reach()
    assert calls == ["tool0", "wrist_2_link"]
    assert second == first
    assert 0.3 < shorter < first < 0.7  # the UR3 reaches about 0.5 m to its flange
