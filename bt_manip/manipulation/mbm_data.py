"""The public MotionBenchMaker problem sets, fetched once into bt-manip's cache.

VAMP's source distribution (PyPI ``vamp-planner``, Apache-2.0; the problems are
MotionBenchMaker's, BSD-3) carries, per robot, ``resources/<robot>/`` with the robot's URDF
(meshes as ``package://meshes/...``, relative to that folder), its SRDF and
``problems.tar.bz2`` (``problems/<family>_<robot>/sceneNNNN.yaml`` + ``requestNNNN.yaml``, seven
families of 100). :func:`fetch_mbm` downloads that sdist with pip (no build, no
dependencies), unpacks the robot's folder and its problems into
``$XDG_CACHE_HOME/bt-manip/mbm`` (``$BT_MANIP_MBM_CACHE`` overrides it), and answers where they
are; a second call finds them there. Data, never shipped with bt-manip.
"""

from __future__ import annotations

import shutil
import subprocess
import sys
import tarfile
import tempfile
from dataclasses import dataclass
from pathlib import Path

from bt_manip.cache import cache_dir

__all__ = ["VAMP_VERSION", "MbmData", "MbmUnavailable", "fetch_mbm", "mbm_cache"]

VAMP_VERSION = "0.6.4"
"""The ``vamp-planner`` sdist the problems are taken from."""


class MbmUnavailable(RuntimeError):
    """The problems cannot be fetched (no network, pip failing, an unexpected archive)."""


@dataclass(frozen=True)
class MbmData:
    """One robot's files: its URDF, SRDF and the folder of its family folders."""

    urdf: Path
    srdf: Path
    problems: Path

    def families(self) -> list[Path]:
        return sorted(p for p in self.problems.iterdir() if p.is_dir())


def mbm_cache() -> Path:
    """Where the problems are kept (not created here)."""
    return cache_dir("mbm", "BT_MANIP_MBM_CACHE")


def _data(root: Path, robot: str) -> MbmData:
    folder = root / robot
    return MbmData(folder / f"{robot}.urdf", folder / f"{robot}.srdf", folder / "problems")


def fetch_mbm(robot: str = "panda", timeout_s: float = 600.0) -> MbmData:
    """The files of ``robot`` (panda, ur5, fetch, baxter), fetched when not in the cache yet.
    Raises :class:`MbmUnavailable` saying why when they cannot be had."""
    root = mbm_cache() / f"vamp-{VAMP_VERSION}"
    data = _data(root, robot)
    if data.urdf.is_file() and data.srdf.is_file() and data.problems.is_dir():
        return data
    root.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(dir=root) as tmp:
        work = Path(tmp)
        command = [sys.executable, "-m", "pip", "download", "--no-deps", "--no-binary",
                   "vamp-planner", f"vamp-planner=={VAMP_VERSION}", "-d", str(work)]
        try:
            done = subprocess.run(command, capture_output=True, text=True, timeout=timeout_s,
                                  check=False)
        except (OSError, subprocess.TimeoutExpired) as exc:
            raise MbmUnavailable(f"pip download of vamp-planner=={VAMP_VERSION}: {exc}") from None
        sdists = sorted(work.glob("vamp*planner-*.tar.gz"))
        if done.returncode != 0 or not sdists:
            tail = (done.stderr or done.stdout).strip().splitlines()[-1:] or ["no output"]
            raise MbmUnavailable(f"pip download of vamp-planner=={VAMP_VERSION} failed: "
                                 f"{tail[0]}")
        staged = work / robot
        _unpack_robot(sdists[0], robot, staged)
        with tarfile.open(staged / "problems.tar.bz2") as archive:
            archive.extractall(staged, filter="data")
        (staged / "problems.tar.bz2").unlink()
        target = root / robot
        if target.exists():
            shutil.rmtree(target)
        staged.rename(target)
    if not (data.urdf.is_file() and data.problems.is_dir()):
        raise MbmUnavailable(f"the vamp-planner sdist has no resources/{robot} with a URDF and "
                             "problems")
    return data


def _unpack_robot(sdist: Path, robot: str, target: Path) -> None:
    """``resources/<robot>/`` of the sdist (its URDF, SRDF, meshes, problems) into ``target``."""
    with tarfile.open(sdist) as archive:
        members = []
        for member in archive.getmembers():
            parts = Path(member.name).parts
            if len(parts) > 3 and parts[1:3] == ("resources", robot):
                member.name = str(Path(*parts[3:]))
                members.append(member)
        if not members:
            raise MbmUnavailable(f"{sdist.name} has no resources/{robot}/")
        archive.extractall(target, members=members, filter="data")
