"""Contact checks used by robot behaviours: did the arm, or what it carries, hit something?

"Something" is the static world (walls, furniture) and the floor. Touching movable objects is
allowed (grasping needs contact), and so is the robot's base touching the floor (its wheels).
"""

from __future__ import annotations

from typing import Any

from bt_manip.sim import pybullet_queries as pbq


def arm_link_ids(robot: Any) -> frozenset[int]:
    """PyBullet link indices of the arm and gripper of ``robot``."""
    links: frozenset[int] = robot.arm_link_set()
    return links


def _static_ids(world: Any) -> dict[int, str]:
    return {
        info.body_id: info.name
        for info in world.infos.values()
        if info.kind in ("wall", "furniture", "ground")
    }


def arm_collisions(world: Any, robot: Any) -> list[str]:
    """Descriptions of contacts between the arm (or what it holds) and the static world."""
    links = arm_link_ids(robot)
    static: dict[int, str] | None = None
    found: list[str] = []
    for link, other in pbq.contact_links(world.client, robot.body):
        if link in links:
            if static is None:
                static = _static_ids(world)
            if other in static:
                found.append(f"{robot.link_name(link)} touched '{static[other]}'")
    found += carried_collisions(world, robot)
    return sorted(set(found))


def carried_collisions(world: Any, robot: Any, robot_name: str | None = None) -> list[str]:
    """Contacts between objects attached to ``robot`` and the static world (the supports an
    object rested on when it was attached do not count until it has left them)."""
    name = robot_name or next((n for n, r in world.robots.items() if r is robot), "")
    found = []
    for held in world.attachments.held_by(name):
        for other in world.attachments.static_contacts(held.object_name):
            found.append(f"carried '{held.object_name}' touched '{other}'")
    return found
