"""Breakpoints set over the Groot2 protocol pause Scenario A (tree and simulation) until
unlocked, and the unlock's status decides how the run goes on."""

from __future__ import annotations

import json
import threading
import time
from pathlib import Path
from typing import Any

import zmq
from groot_client import GrootClient, sync_subscription

from bt_manip.bt.xml_parse import parse_xml_text
from bt_manip.episode import Episode, EpisodeSpec
from bt_manip.groot import GrootPublisher
from bt_manip.run.runner import RunOptions

ROOT = Path(__file__).resolve().parents[2]


def uid_of(fulltree: str, name: str) -> int:
    root = parse_xml_text(fulltree, "fulltree.xml")
    stack = list(root.children)
    while stack:
        element = stack.pop()
        if element.get("name") == name and element.get("_uid"):
            return int(element.get("_uid") or 0)
        stack += element.children
    raise KeyError(name)


def status_of(status_reply: bytes, uid: int) -> int:
    for offset in range(0, len(status_reply), 3):
        if int.from_bytes(status_reply[offset:offset + 2], "little") == uid:
            return status_reply[offset + 2]
    raise KeyError(uid)


def wait_for_breakpoint(client: GrootClient, run: threading.Thread, limit_s: float = 600) -> list:
    """Poll STATUS as Groot2 does (each request is a heartbeat) until the PUB message."""
    deadline = time.monotonic() + limit_s
    client.sub.setsockopt(zmq.RCVTIMEO, 200)
    while time.monotonic() < deadline and run.is_alive():
        try:
            return client.sub.recv_multipart()
        except zmq.Again:
            client.request("S")
    raise AssertionError("no breakpoint reached")


def test_breakpoint_on_attach_panel_freezes_sim_time_and_unlock_decides() -> None:
    spec = EpisodeSpec(tree=str(ROOT / "trees/husky_carry_wall.xml"),
                       world=str(ROOT / "worlds/tb3_house.yaml"), seed=0,
                       options=RunOptions(max_sim_time=120.0))
    with Episode(spec) as episode:
        publisher = GrootPublisher(episode.monitor(), port=0)
        client = GrootClient(publisher.port)
        sync_subscription(client, publisher)
        outcome: dict[str, Any] = {}
        run = threading.Thread(target=lambda: outcome.update(report=episode.run()))
        try:
            fulltree = client.request("T")[1].decode()
            attach, release = uid_of(fulltree, "attach_panel"), uid_of(fulltree, "release")
            hook = {"enabled": True, "uid": attach, "mode": 0, "once": False,
                    "desired_status": "IDLE", "position": 0}
            assert client.request("I", json.dumps(hook))[0][6:] == publisher.uuid
            run.start()

            # First grasp attempt: paused before attach_panel ticks.
            message = wait_for_breakpoint(client, run)
            assert len(message[0]) == 6 and message[0][:2] == b"\x02N"  # then a random id
            assert message[1] == str(attach).encode()
            assert publisher.paused_uid == attach
            frozen = episode.world.time
            status = client.request("S")[1]
            assert status_of(status, attach) == 0  # IDLE: not ticked yet
            time.sleep(0.5)
            assert run.is_alive() and episode.world.time == frozen
            assert client.request("S")[1] == status
            assert not episode.world.attachments.is_attached("panel", None)
            unlock = {"uid": attach, "desired_status": "FAILURE", "position": 0,
                      "remove_when_done": False}
            assert client.request("U", json.dumps(unlock))[0][6:] == publisher.uuid

            # FAILURE: the grasp backs off (release, arm_back) and is tried again.
            message = wait_for_breakpoint(client, run)
            assert message[1] == str(attach).encode()
            frozen = episode.world.time
            status = client.request("S")[1]
            assert status_of(status, attach) == 13  # IDLE, after its forced FAILURE
            assert status_of(status, release) == 12  # IDLE, after releasing
            time.sleep(0.5)
            assert episode.world.time == frozen
            unlock.update(desired_status="SUCCESS", remove_when_done=True)
            client.request("U", json.dumps(unlock))
            run.join(600)
            assert json.loads(client.request("D")[1]) == []
        finally:
            publisher.close()
            run.join(600)
            client.close()
        report = outcome["report"]
        # SUCCESS replaced the attach: the lift goes on, but the panel was never attached.
        assert report.status == "FAILURE"
        assert "panel_attached" in report.reason and "is not attached" in report.reason
        assert not episode.world.attachments.is_attached("panel", None)
        lift = next(n for n in report.nodes if n.path.endswith("/lift_panel"))
        assert lift.last_status == "SUCCESS"
