"""Scenario B with the bin at the edge of the Sawyer's reach (worlds/sawyer_table_bin_far.yaml):
DropPoint sends the blocks meant for the cells the arm cannot reach to cells it reaches, so the
blocks still end in the bin."""

from __future__ import annotations

from pathlib import Path

from bt_manip.episode import Episode, EpisodeSpec

ROOT = Path(__file__).resolve().parents[2]


def test_the_blocks_end_in_the_far_bin() -> None:
    spec = EpisodeSpec(tree=str(ROOT / "trees" / "sawyer_blocks_to_bin.xml"),
                       world=str(ROOT / "worlds" / "sawyer_table_bin_far.yaml"), seed=7)
    with Episode(spec) as episode:
        report = episode.run()
        assert report.status == "SUCCESS", report.reason
        blackboard = episode.tree.blackboard.as_dict()
        assert blackboard["resting_in_bin"] >= 9, blackboard
        # every drop point was one the arm reaches: no move over the bin failed
        over_bin = [n for n in report.nodes if n.path.endswith("/over_bin") and n.reason]
        assert over_bin == []
