"""The bench's Ray backend: the episodes of a bench as Ray tasks, on a local or remote cluster.

``bt-manip bench ... --backend ray [--address ADDR]`` (Ray is the optional extra
``bt-manip[ray]``). Each episode is one task that builds its own PyBullet client and world in
the worker, exactly as a worker process of the default backend does, so a seed gives the same
episode on either backend.

What the workers need travels in the job's runtime environment:

- ``py_modules``: this bt_manip package, so the cluster needs no bt-manip installed;
- ``working_dir``: the current directory (the tree, world and robot files, which must lie
  under it; ``.git``, ``.venv``, ``out`` and caches are left out), where the tasks run, so
  the bench's relative paths mean the same there;
- ``pip`` (only with ``--address``, a cluster that may lack them): bt-manip's own
  dependencies, as pyproject.toml lists them.

Without ``--address`` a local Ray instance is started with ``jobs`` CPUs and stopped at the
end. With one, ``ADDR`` is any address ``ray.init`` takes (``ray://head:10001``, ``auto``).
"""

from __future__ import annotations

import os
import re
from collections.abc import Callable
from dataclasses import replace
from importlib import metadata
from pathlib import Path
from typing import TYPE_CHECKING, Any

import bt_manip
from bt_manip.bench.episodes import EpisodeResult, run_one
from bt_manip.errors import InputError

if TYPE_CHECKING:
    from bt_manip.episode import EpisodeSpec

EXCLUDES = [".git", ".venv", "venv", "out", "__pycache__", "*.pyc", ".pytest_cache",
            ".mypy_cache", ".ruff_cache", "*.btlog", "*.egg-info"]
"""What the working directory sent to the cluster leaves out."""


def _declared() -> list[str]:
    """bt-manip's runtime requirements as its metadata (or, from a clone, pyproject.toml)
    declares them."""
    try:
        return [r for r in metadata.requires("bt-manip") or [] if "extra ==" not in r]
    except metadata.PackageNotFoundError:
        import tomllib

        pyproject = Path(bt_manip.__file__).resolve().parents[1] / "pyproject.toml"
        with open(pyproject, "rb") as fh:
            return list(tomllib.load(fh)["project"]["dependencies"])


def dependencies() -> list[str]:
    """bt-manip's runtime requirements, pinned to the versions installed here where there are
    any (name==version), for a cluster's runtime environment."""
    pinned = []
    for req in _declared():
        name = re.split(r"[\s;<>=!~\[]", req.strip(), maxsplit=1)[0]
        try:
            pinned.append(f"{name}=={metadata.version(name)}")
        except metadata.PackageNotFoundError:
            pinned.append(req.split(";")[0].strip())
    return pinned


def _relative(path: str | None, root: Path) -> str | None:
    """``path`` relative to ``root`` (the working directory the tasks run in); InputError when
    it lies outside."""
    if not path:
        return path
    p = Path(path).resolve()
    try:
        return str(p.relative_to(root))
    except ValueError:
        raise InputError.single(
            path, None, "--backend ray ships the current directory to the cluster: this file "
                        f"is outside {root}; run the bench from a folder that holds it"
        ) from None


def runtime_env(remote: bool, root: Path) -> dict[str, Any]:
    """The runtime environment of the bench's Ray job (see the module docstring)."""
    env: dict[str, Any] = {
        "working_dir": str(root),
        "excludes": list(EXCLUDES),
        "py_modules": [str(Path(bt_manip.__file__).parent)],
    }
    if remote:
        env["pip"] = dependencies()
    return env


def run_on_ray(specs: list[EpisodeSpec], finished: Callable[[EpisodeResult], None],
               address: str | None = None, jobs: int = 1) -> None:
    """Run ``specs`` as Ray tasks; ``finished`` gets each result as its task completes. A
    Ctrl-C (or an error) cancels the tasks not done; a local instance started here is
    stopped at the end."""
    try:
        import ray
    except ImportError:
        raise InputError.single(
            "--backend", None, "ray is not installed: pip install 'bt-manip[ray]'") from None

    root = Path(os.getcwd()).resolve()
    specs = [
        replace(s, tree=_relative(s.tree, root) or s.tree, world=_relative(s.world, root),
                models=[_relative(m, root) or m for m in s.models],
                btlog=None)
        for s in specs
    ]
    env = runtime_env(address is not None, root)
    os.environ.setdefault("RAY_ACCEL_ENV_VAR_OVERRIDE_ON_ZERO", "0")  # no GPUs asked for
    started_here = not ray.is_initialized()
    if started_here:
        if address is None:
            ray.init(num_cpus=max(1, jobs), include_dashboard=False, runtime_env=env,
                     log_to_driver=False, configure_logging=False)
        else:
            ray.init(address=address, runtime_env=env, log_to_driver=False,
                     configure_logging=False)
    task = ray.remote(num_cpus=1, max_retries=0)(run_one)
    pending = [task.remote(s) for s in specs]
    try:
        while pending:
            done, pending = ray.wait(pending, num_returns=1)
            for ref in done:
                finished(ray.get(ref))
    except BaseException:
        for ref in pending:
            ray.cancel(ref, force=True)
        raise
    finally:
        if started_here:
            ray.shutdown()
