"""Build step of bt-manip's wheel: the example folders and the JSON Schemas become package data.

The project's metadata is in pyproject.toml. The example trees, worlds and robots stay at the
top of the repository (``trees/``, ``worlds/``, ``robots/``, where users and the docs look for
them); a wheel carries copies of them as ``bt_manip/_data/<folder>/``, where
``bt_manip.sim.assets.data_root`` finds them once installed. The JSON Schemas of the output
files stay in ``docs/schemas/`` and go to ``bt_manip/_data/schemas/`` (``bt_manip.schemas``,
``bt-manip schema``). An editable install (``pip install -e .``) copies nothing: bt_manip then
reads the folders of the clone itself.
"""

from __future__ import annotations

import os
import shutil
from pathlib import Path

from setuptools import setup
from setuptools.command.build_py import build_py

HERE = Path(__file__).resolve().parent
EXAMPLE_FOLDERS = ("trees", "worlds", "robots")
DATA_FOLDERS = {**{folder: folder for folder in EXAMPLE_FOLDERS}, "schemas": "docs/schemas"}
"""Each folder of ``bt_manip/_data`` and the folder of the clone it is copied from."""
SKIPPED = shutil.ignore_patterns("__pycache__", "*.pyc", ".*")


class BuildWithExamples(build_py):
    """``build_py`` that also copies the example folders and the schemas into
    ``bt_manip/_data``."""

    def run(self) -> None:
        super().run()
        if getattr(self, "editable_mode", False):
            return
        target = Path(self.build_lib) / "bt_manip" / "_data"
        for folder, origin in DATA_FOLDERS.items():
            source = HERE / origin
            if not source.is_dir():
                raise FileNotFoundError(f"{source}: the wheel's data folder is missing")
            destination = target / folder
            if destination.exists():
                shutil.rmtree(destination)
            shutil.copytree(source, destination, ignore=SKIPPED)
            self.announce(f"copied {origin}/ to {os.fspath(destination)}", level=2)


setup(cmdclass={"build_py": BuildWithExamples})
