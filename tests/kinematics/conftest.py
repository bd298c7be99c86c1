"""Shared arms for the kinematics tests: the UR3, the Sawyer and a synthetic mobile manipulator."""

from __future__ import annotations

from pathlib import Path

import pytest
from kin_helpers import SAWYER_URDF, composite_urdf_text

from bt_manip.kinematics import ArmModel
from bt_manip.sim.assets import ur3_urdf


@pytest.fixture(scope="session")
def composite_urdf(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("robots") / "composite.urdf"
    path.write_text(composite_urdf_text())
    return path


@pytest.fixture(scope="session")
def ur3() -> ArmModel:
    return ArmModel.from_urdf(ur3_urdf(), "base_link", "tool0")


@pytest.fixture(scope="session")
def sawyer() -> ArmModel:
    if not SAWYER_URDF.is_file():
        pytest.skip(f"{SAWYER_URDF} not found")
    return ArmModel.from_urdf(SAWYER_URDF, "right_arm_base_link", "right_hand")


@pytest.fixture(scope="session")
def composite(composite_urdf: Path) -> ArmModel:
    return ArmModel.from_urdf(composite_urdf, "arm_base", "tool")
