"""Where robot and world assets live on this machine.

Committed files never hold absolute paths. URDFs refer to meshes through URIs that are resolved
here at load time:

- ``package://example-robot-data/...``: the ``example-robot-data`` wheel, installed under
  ``<site-packages>/cmeel.prefix/share/``.
- ``pybullet_data://...``: the data folder that ships with ``pybullet``.
- plain relative paths: relative to the file that names them.

The example trees, worlds and robots live at the top of a clone (``trees/``, ``worlds/``,
``robots/``); a built wheel carries the same folders as package data under
``bt_manip/_data/`` (see ``setup.py``). :func:`data_root` is whichever of the two this copy of
bt_manip has.
"""

from __future__ import annotations

import functools
from importlib import metadata
from pathlib import Path

REPO_ROOT = Path(__file__).resolve().parents[2]
"""The checkout (or source tree) that holds ``robots/``, ``worlds/`` and ``trees/``."""

PACKAGED_DATA = Path(__file__).resolve().parents[1] / "_data"
"""Where an installed wheel keeps its copies of ``robots/``, ``worlds/`` and ``trees/``."""

DATA_FOLDERS = ("trees", "worlds", "robots")
"""The folders of examples that ship with bt-manip, in the order they are listed."""


def data_root() -> Path:
    """The folder that holds the shipped ``trees/``, ``worlds/`` and ``robots/``.

    An installed wheel's package data when there is one, else the clone bt_manip was imported
    from (an editable install or ``PYTHONPATH``).
    """
    if (PACKAGED_DATA / "robots").is_dir():
        return PACKAGED_DATA
    return REPO_ROOT


def shipped_or_given(text: str) -> str:
    """A tree or world path as the file to read: ``text`` itself when that file exists (paths
    are relative to the current folder, as always) or when it does not name a shipped file;
    else, for a relative path into the shipped folders (``trees/husky_carry_wall.xml``,
    ``worlds/tb3_house.yaml``), the shipped file."""
    given = Path(text)
    if given.exists() or given.is_absolute():
        return text
    parts = given.parts
    if len(parts) < 2 or parts[0] not in DATA_FOLDERS or ".." in parts:
        return text
    shipped = data_root() / given
    return str(shipped) if shipped.is_file() else text


@functools.cache
def example_robot_data_share() -> Path:
    """The ``share`` folder that holds ``example-robot-data/robots/...``."""
    dist = metadata.distribution("example-robot-data")
    share = Path(str(dist.locate_file("cmeel.prefix/share")))
    if not (share / "example-robot-data").is_dir():
        raise FileNotFoundError(f"example-robot-data assets not found under {share}")
    return share


@functools.cache
def pybullet_data_dir() -> Path:
    """The data folder shipped with pybullet (``husky/``, ``plane.urdf``, ...)."""
    import pybullet_data

    return Path(pybullet_data.getDataPath())


def ur3_urdf() -> Path:
    """The UR3 description of example-robot-data (elbow limited to +-pi, ``world`` link)."""
    return (
        example_robot_data_share() / "example-robot-data/robots/ur_description/urdf/ur3_robot.urdf"
    )


def _in_package(rest: str, folder: Path) -> Path | None:
    """``package://PKG/...`` found beside a URDF, as ROS finds it: the nearest folder above
    ``folder`` named ``PKG`` (the package's root), or a ``PKG`` folder beside one of them."""
    package, _, inner = rest.partition("/")
    for above in (folder.resolve(), *folder.resolve().parents):
        for root in (above, above / package):
            if root.name == package and (root / inner).exists():
                return (root / inner).resolve()
    return None


def resolve_uri(uri: str, relative_to: Path | None = None) -> Path:
    """Turn an asset URI into an absolute path on this machine (the file may not exist)."""
    if uri.startswith("package://"):
        # "package:///pkg/..." (an empty host, as Talos' full URDFs write it) is "package://pkg/..."
        rest = uri[len("package://") :].lstrip("/")
        shared = example_robot_data_share() / rest
        if shared.exists() or relative_to is None:
            return shared
        return _in_package(rest, relative_to) or shared
    if uri.startswith("pybullet_data://"):
        return pybullet_data_dir() / uri[len("pybullet_data://") :]
    if uri.startswith("file://"):
        uri = uri[len("file://") :]
    p = Path(uri)
    if not p.is_absolute() and relative_to is not None:
        p = relative_to / p
    return p.resolve()
