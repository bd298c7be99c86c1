"""bt-manip as a package: `python -m build` gives an sdist and a wheel; the wheel, installed
with pip into a fresh venv (its dependencies from the package index, through pip's cache), runs
`bt-manip demo` from an empty folder, with nothing of the clone on its path.

The slowest test of the suite (a minute or two: the build, the install, one Scenario A run);
kept to one test so that it is paid once.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tarfile
import zipfile
from pathlib import Path

import bt_manip

ROOT = Path(__file__).resolve().parents[1]
SHIPPED = ("trees", "worlds", "robots")


def _run(argv: list[str], cwd: Path, timeout: float) -> subprocess.CompletedProcess[str]:
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "PYTHONHOME")}
    env["PYTHONNOUSERSITE"] = "1"
    return subprocess.run(argv, cwd=cwd, env=env, capture_output=True, text=True,
                          timeout=timeout, stdin=subprocess.DEVNULL)


SCHEMAS = ROOT / "docs" / "schemas"


def _shipped_files() -> set[str]:
    return {p.relative_to(ROOT).as_posix() for folder in SHIPPED
            for p in (ROOT / folder).rglob("*") if p.is_file()}


def _schema_files() -> set[str]:
    """The JSON Schemas, as the wheel keeps them (``bt_manip/_data/schemas/...``)."""
    return {f"schemas/{p.name}" for p in SCHEMAS.iterdir() if p.is_file()}


def test_the_wheel_installs_in_a_fresh_venv_and_runs_the_demo_from_an_empty_folder(
        tmp_path: Path) -> None:
    dist = tmp_path / "dist"
    built = _run([sys.executable, "-m", "build", "--outdir", str(dist), str(ROOT)],
                 tmp_path, 600)
    assert built.returncode == 0, built.stdout[-3000:] + built.stderr[-3000:]
    (wheel,) = dist.glob("bt_manip-*.whl")
    (sdist,) = dist.glob("bt_manip-*.tar.gz")
    assert wheel.name == f"bt_manip-{bt_manip.__version__}-py3-none-any.whl"

    # the wheel: the package, its examples as package data, nothing else of the clone
    with zipfile.ZipFile(wheel) as archive:
        names = archive.namelist()
    tops = {n.split("/")[0] for n in names}
    assert tops == {"bt_manip", f"bt_manip-{bt_manip.__version__}.dist-info"}
    data = {n.removeprefix("bt_manip/_data/") for n in names if n.startswith("bt_manip/_data/")}
    assert data == _shipped_files() | _schema_files()
    assert "schemas/run-report.schema.json" in data
    assert "bt_manip/viz/static/replay.js" in names
    assert not any("__pycache__" in n or n.endswith(".pyc") for n in names)
    # the sdist carries the example folders the wheel is built from, not the tests
    with tarfile.open(sdist) as archive:
        members = {m.split("/", 1)[1] for m in archive.getnames() if "/" in m}
    assert _shipped_files() <= members and "CHANGELOG.md" in members
    assert {f"docs/{name}" for name in _schema_files()} <= members
    assert not any(m.startswith(("tests/", "out/", ".venv/")) for m in members)

    venv = tmp_path / "venv"
    made = _run([sys.executable, "-m", "venv", str(venv)], tmp_path, 300)
    assert made.returncode == 0, made.stderr
    # --no-compile: no .pyc written ahead for the 2 GB of dependencies (Python compiles what
    # the run imports as it imports it); what is installed, and from where, is the same
    installed = _run([str(venv / "bin" / "python"), "-m", "pip", "install",
                      "--disable-pip-version-check", "--no-compile", str(wheel)], tmp_path, 900)
    assert installed.returncode == 0, installed.stdout[-3000:] + installed.stderr[-3000:]

    empty = tmp_path / "empty"
    empty.mkdir()
    cli = str(venv / "bin" / "bt-manip")
    version = _run([cli, "--version"], empty, 120)
    assert version.stdout.strip() == f"bt-manip {bt_manip.__version__}", version.stderr
    where = _run([str(venv / "bin" / "python"), "-c",
                  "import site, bt_manip.sim.assets as a, bt_manip.schemas as s; "
                  "print(a.data_root()); print(site.getsitepackages()[0]); "
                  "print(s.schema_path('run-report'))"], empty, 120)
    data_root, site_packages, schema = where.stdout.split()
    assert Path(data_root) == Path(site_packages) / "bt_manip" / "_data", where.stderr
    # what `bt-manip schema run-report` prints: the wheel's copy of the run report's schema
    assert Path(schema) == Path(data_root) / "schemas" / "run-report.schema.json"
    assert Path(schema).read_bytes() == (SCHEMAS / "run-report.schema.json").read_bytes()

    demo = _run([cli, "demo", "--quiet"], empty, 600)
    assert demo.returncode == 0, demo.stdout[-3000:] + demo.stderr[-3000:]
    assert "result: SUCCESS" in demo.stdout
    assert "Traceback" not in demo.stderr
    report = json.loads((empty / "husky_report.json").read_text())
    assert report["status"] == "SUCCESS" and report["schema_version"] == 1
    assert Path(report["world"]).parts[-3:] == ("_data", "worlds", "tb3_house.yaml")
    page = (empty / "husky_replay.html").read_text()
    assert page.startswith("<!DOCTYPE html>")
    assert "<title>husky_carry_wall.xml (replay)</title>" in page
    assert sorted(p.name for p in empty.iterdir()) == ["husky_replay.html", "husky_report.json"]
