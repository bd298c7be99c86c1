"""What a process remembers between episodes (IK functions, drawn obstacle cells, ...) never
changes an episode: run after episodes of other worlds and robots, an episode gives what it
gives in a fresh process."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from dataclasses import asdict
from pathlib import Path

from bt_manip.bench.episodes import run_one
from bt_manip.episode import EpisodeSpec

ROOT = Path(__file__).resolve().parents[1]
OMNI = (str(ROOT / "trees" / "omni_sawyer_pick.xml"),
        str(ROOT / "worlds" / "omni_sawyer_room.yaml"))
PANDA = (str(ROOT / "trees" / "panda_pick_place.xml"), str(ROOT / "worlds" / "panda_table.yaml"))

FRESH = """
import json, sys
from dataclasses import asdict
from bt_manip.bench.episodes import run_one
from bt_manip.episode import EpisodeSpec
r = asdict(run_one(EpisodeSpec(tree=sys.argv[1], world=sys.argv[2], seed=int(sys.argv[3]))))
r.pop("wall_time")
print(json.dumps(r))
"""


def _outcome(tree: str, world: str, seed: int) -> dict[str, object]:
    r = asdict(run_one(EpisodeSpec(tree=tree, world=world, seed=seed)))
    r.pop("wall_time")
    return json.loads(json.dumps(r))  # as the fresh process reports it


def test_an_episode_after_other_worlds_and_robots_equals_one_in_a_fresh_process() -> None:
    _outcome(*OMNI, 3)   # a navigating robot: its grids and footprint drawn
    _outcome(*PANDA, 2)  # another robot, another arm chain, another world
    after_others = _outcome(*OMNI, 5)
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    done = subprocess.run([sys.executable, "-c", FRESH, *OMNI, "5"], capture_output=True,
                          text=True, env=env, check=True, timeout=300)
    fresh = json.loads(done.stdout.strip().splitlines()[-1])
    assert after_others["status"] == "SUCCESS"
    assert after_others == fresh
